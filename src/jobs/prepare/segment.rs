//! A segmentation job from its spec: the image's automatic settings
//! ([`super::preprocess`]), the automatic initial shape (threshold contours,
//! seeds, or the inscribed circle/sphere) and the functional (Chan–Vese,
//! geodesic, or both). Every automatic choice is kept in a [`SegmentationSetup`]
//! that the results report.

use super::checks::positive;
use super::image_shapes::{inscribed, seeds, threshold_mesh, threshold_objects, RegionWeights, TouchingSplit};
use super::inputs::load_image;
use super::preprocess::{preprocess, smoothed_away, Preprocessed};
use super::ProblemKind;
use crate::geometry::AnyMesh;
use crate::imaging::labels::territories;
use crate::imaging::{EdgeField, Grid, Plane};
use crate::jobs::necks::NeckSplit;
use crate::jobs::spec::bounds::{CHANNEL, MIN_SEPARATION, MIN_SIZE, TIME_POINT, WEIGHT};
use crate::jobs::spec::{
    BackgroundModel, InitialSpec, InscribedShape, MeansKind, Polarity, SeedsShape, SegmentationModel, SegmentationSpec,
    SpecError, ThresholdShape,
};
use crate::problems::{ChanVese, Segmentation, Territories};
use serde::Serialize;
use std::collections::HashMap;
use std::sync::Arc;

/// Default `problem.mu` (intensity² × pixels) for noise of standard deviation
/// `noise` (normalized scale) on a curve: `max(0.05, noise/2)`. The fit of an
/// unsmoothed image along a contour fluctuates with the noise; the length term has
/// to outweigh that at the scale of a pixel.
pub fn default_mu(noise: f64) -> f64 {
    (0.5 * noise).max(0.05)
}

/// Default `problem.mu` in dimension `d`: [`default_mu`] divided by `d − 1`. The
/// length term pulls a contour in with `μκ`, and a surface's mean curvature is the
/// sum of its two principal curvatures: a ball of radius `r` has `κ = 2/r` where a
/// disc has `1/r`. Dividing by `d − 1` gives objects of one radius the same pull,
/// hence the same inward shift of their edges, in 2D and 3D.
pub fn default_mu_in(noise: f64, d: usize) -> f64 {
    default_mu(noise) / (d.max(2) - 1) as f64
}

/// The settings a segmentation ran with, automatic or given (shape.json and the
/// job's results report them).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentationSetup {
    pub model: SegmentationModel,
    /// The percentiles and the intensities mapped to 0 and 1.
    pub percentiles: [f64; 2],
    pub intensity_range: [f64; 2],
    /// Standard deviation of the noise on the normalized scale (Immerkær).
    pub noise: f64,
    /// Gaussian smoothing (pixels) of the image the threshold and the edge
    /// indicator see.
    pub sigma: f64,
    /// Gaussian smoothing (pixels) of the image the Chan–Vese fit sees.
    pub data_sigma: f64,
    pub background: BackgroundModel,
    /// The range (largest minus smallest value) of the illumination removed.
    pub illumination_range: f64,
    pub polarity: Polarity,
    /// Threshold of the automatic initial shape (normalized scale).
    pub threshold: f64,
    /// The more permissive threshold for dim objects that the main one misses
    /// entirely (`None` where it is not more permissive).
    pub dim_threshold: Option<f64>,
    /// The contrast scale `k` of the edge indicator `H = 1/(1 + |∇I_σ|²/k²)`
    /// (image on [0, 100]); `None` for the Chan–Vese model, which has no `H`.
    pub edge_contrast: Option<f64>,
    pub min_size: f64,
    /// Objects of the initial shape.
    pub initial_objects: usize,
    pub mu: f64,
    pub lambda_in: f64,
    pub lambda_out: f64,
    pub means: MeansKind,
    pub merge: bool,
    /// Volumes: the voxel spacing of the results' grid (cubic after an anisotropic
    /// input's resampling) and where its first voxel lies, in the input file's
    /// units and space (NRRD's `space origin`, NIfTI's transform in
    /// left-posterior-superior coordinates; 0 for TIFF stacks), as mask.nrrd and
    /// labels.nrrd record them with the axes' directions. `None` for 2D images.
    pub voxel_spacing: Option<[f64; 3]>,
    pub voxel_origin: Option<[f64; 3]>,
}

/// What [`prepare_segmentation`] builds.
pub(super) struct PreparedSegmentation {
    pub grid: Grid,
    pub problem: ProblemKind,
    pub second_stage: Option<ProblemKind>,
    pub edges: Option<Arc<EdgeField>>,
    /// The initial shape when it comes from the image (`None`: built from the spec).
    pub mesh: Option<AnyMesh>,
    pub setup: SegmentationSetup,
    pub neck_split: Option<NeckSplit>,
}

pub(super) fn prepare_segmentation(
    spec: &SegmentationSpec,
    initial: Option<&InitialSpec>,
    inputs: &HashMap<String, Vec<u8>>,
) -> Result<PreparedSegmentation, SpecError> {
    if let Some(c) = spec.channel {
        CHANNEL.check("problem.channel", c)?;
    }
    if let Some(t) = spec.time_point {
        TIME_POINT.check("problem.time_point", t)?;
    }
    let plane = Plane { channel: spec.channel.map(|c| c as usize), time_point: spec.time_point.map(|t| t as usize) };
    let grid = load_image(&spec.image, plane, inputs)?;
    let model = spec.model.unwrap_or(SegmentationModel::ChanVese);
    let pre = preprocess(spec, &grid, model)?;
    let d = grid.dimension;
    let min_size = match spec.min_size {
        Some(m) => MIN_SIZE.check("problem.min_size", m)?,
        None => default_min_size(d),
    };
    let mu = WEIGHT.check("problem.mu", spec.mu.unwrap_or(default_mu_in(pre.noise, d)))?;
    let lambda_in = WEIGHT.check("problem.lambda_in", spec.lambda_in.unwrap_or(1.0))?;
    let lambda_out = WEIGHT.check("problem.lambda_out", spec.lambda_out.unwrap_or(1.0))?;
    // the geodesic model's weights are checked whichever model runs
    for (field, v) in [("problem.lambda", spec.lambda), ("problem.lambda_final", spec.lambda_final)] {
        if let Some(v) = v.filter(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(SpecError::new(field, format!("must be a nonnegative number, got {v}")));
        }
    }
    if let Some(e) = spec.epsilon {
        positive("problem.epsilon", e)?;
    }
    if let Some(k) = spec.edge_contrast {
        WEIGHT.check("problem.edge_contrast", positive("problem.edge_contrast", k)?)?;
    }
    let means = spec.means.unwrap_or(MeansKind::PerObject);
    let merge = spec.merge.unwrap_or(false);
    let region = RegionWeights { mu, lambda_in, lambda_out };
    let split_touching = spec.split_touching.unwrap_or(true);
    let separation = spec.min_separation.map(|s| MIN_SEPARATION.check("problem.min_separation", s)).transpose()?;
    let split = match (split_touching, separation) {
        (false, _) => TouchingSplit::None,
        (true, None) => TouchingSplit::Necks,
        (true, Some(s)) => TouchingSplit::Peaks(s),
    };
    let start = image_initial(initial, &grid, &pre, region, min_size, split)?;
    let weights = ChanVeseWeights { region, per_object: means == MeansKind::PerObject, merge };
    let (problem, second_stage, edges, edge_contrast) =
        functional(spec, model, &grid, &pre.data, &start, &weights, pre.sigma)?;
    let setup = SegmentationSetup {
        model,
        percentiles: pre.percentiles,
        intensity_range: [pre.normalization.lo, pre.normalization.hi],
        noise: pre.noise,
        sigma: pre.sigma,
        data_sigma: pre.data_sigma,
        background: pre.background,
        illumination_range: pre.illumination,
        polarity: pre.levels.polarity(),
        threshold: pre.levels.main,
        dim_threshold: pre.levels.dim,
        edge_contrast,
        min_size,
        initial_objects: start.objects,
        mu,
        lambda_in,
        lambda_out,
        means,
        merge,
        voxel_spacing: (d == 3).then(|| grid.placement.spacing()),
        voxel_origin: (d == 3).then_some(grid.placement.origin),
    };
    // the converged contours (surfaces) of separate objects are split where the
    // flow brought out a neck
    let separate = matches!(&problem, ProblemKind::ChanVese(cv) if cv.separate);
    let neck_split =
        (separate && split_touching).then(|| NeckSplit::for_grid(&grid, min_size.ceil() as usize, separation));
    Ok(PreparedSegmentation { grid, problem, second_stage, edges, mesh: start.mesh, setup, neck_split })
}

/// The initial shape when it comes from the image.
struct ImageInitial {
    mesh: Option<AnyMesh>,
    objects: usize,
    /// Samples between touching objects, and the background level they get
    /// (volumes).
    cut: Vec<usize>,
    background: Option<f64>,
    /// Volumes with several objects: the territory of every object (the contact
    /// rule of surfaces, [`Territories`]).
    territories: Option<Territories>,
}

/// The initial shape from the image (`initial` omitted, `threshold`, `seeds` or
/// `inscribed`; the threshold's touching objects split by `split`), and the
/// samples that separate its objects.
fn image_initial(
    initial: Option<&InitialSpec>,
    grid: &Grid,
    pre: &Preprocessed,
    region: RegionWeights,
    min_size: f64,
    split: TouchingSplit,
) -> Result<ImageInitial, SpecError> {
    let none = ImageInitial { mesh: None, objects: 0, cut: Vec::new(), background: None, territories: None };
    Ok(match initial {
        None | Some(InitialSpec::Threshold(ThresholdShape {})) => {
            let objects = threshold_objects(&pre.smoothed, &pre.data, region, &pre.levels, min_size, split);
            let territories = (grid.dimension == 3 && objects.count > 1)
                .then(|| Territories::new(territories(&objects.labels, pre.smoothed.dims)));
            match threshold_mesh(&pre.smoothed, &objects)? {
                Some((m, count)) => ImageInitial {
                    mesh: Some(m),
                    objects: count,
                    cut: objects.cleared,
                    background: Some(objects.background),
                    territories,
                },
                // nothing above the threshold (a constant or near-constant image): the
                // flow starts from the inscribed shape and decides; with no object it
                // shrinks away and the run ends `vanished` with an empty result
                None => ImageInitial { mesh: Some(inscribed(grid)?), objects: 0, ..none },
            }
        }
        Some(InitialSpec::Seeds(SeedsShape { spacing, radius })) => {
            let m = seeds(grid, *spacing, *radius)?;
            let objects = match &m {
                AnyMesh::Curve(c) => c.num_components(),
                AnyMesh::Surface(s) => s.num_components(),
            };
            ImageInitial { mesh: Some(m), objects, ..none }
        }
        Some(InitialSpec::Inscribed(InscribedShape {})) => {
            ImageInitial { mesh: Some(inscribed(grid)?), objects: 1, ..none }
        }
        Some(_) => none,
    })
}

/// The weights and switches of the Chan–Vese functional.
struct ChanVeseWeights {
    region: RegionWeights,
    per_object: bool,
    merge: bool,
}

/// A segmentation's functional, its second stage, the edge field the results are
/// refined onto, and that field's contrast scale.
type Functional = (ProblemKind, Option<ProblemKind>, Option<Arc<EdgeField>>, Option<f64>);

/// The functional of `model`, its second stage (geodesic with `lambda_final`) and
/// the edge field the results are refined onto, if any.
fn functional(
    spec: &SegmentationSpec,
    model: SegmentationModel,
    grid: &Grid,
    data: &Grid,
    start: &ImageInitial,
    w: &ChanVeseWeights,
    sigma: f64,
) -> Result<Functional, SpecError> {
    let (d, l) = (grid.dimension, grid.scale());
    // (the weights given in the spec are checked by the caller)
    let geodesic = match model {
        SegmentationModel::ChanVese => None,
        _ => {
            let epsilon = spec.epsilon.unwrap_or(crate::jobs::spec::default_beta_epsilon(l));
            let lambda = spec.lambda.unwrap_or(match model {
                SegmentationModel::Both => 0.0,
                _ => crate::jobs::spec::default_lambda(d, l),
            });
            let (field, k) =
                EdgeField::with_contrast(grid, sigma, spec.edge_contrast).ok_or_else(|| smoothed_away(sigma, grid))?;
            Some((Segmentation { field: Arc::new(field), lambda, epsilon }, k))
        }
    };
    let (geodesic, edge_contrast) = match geodesic {
        Some((g, k)) => (Some(g), Some(k)),
        None => (None, None),
    };
    if let (SegmentationModel::Geodesic, Some(problem)) = (model, &geodesic) {
        let lambda_final = spec.lambda_final.unwrap_or(crate::jobs::spec::default_lambda_final(d, problem.lambda));
        let second = (lambda_final != problem.lambda)
            .then(|| ProblemKind::Segmentation(Segmentation { lambda: lambda_final, ..problem.clone() }));
        let edges = spec.edge_refinement.unwrap_or(true).then(|| problem.field.clone());
        return Ok((ProblemKind::Segmentation(problem.clone()), second, edges, edge_contrast));
    }
    let mut values = data.values.clone();
    if let (Some(bg), 3) = (start.background, d) {
        // surfaces: the samples between touching objects get the background level,
        // so that the surfaces stay apart. The territories hold vertices, not
        // triangles: without this, two touching balls' volumes summed to 14 % more
        // than their union. Curves' contact rule tests the segments themselves, and
        // their samples are left as they are, so that touching contours close in on
        // each other
        for &p in &start.cut {
            values[p] = bg;
        }
    }
    let RegionWeights { mu, lambda_in, lambda_out } = w.region;
    let mut cv = ChanVese::new(d, grid.dims, &values, mu / l, (lambda_in, lambda_out));
    cv.per_object = w.per_object;
    cv.separate = w.per_object && !w.merge;
    cv.territories = if cv.separate { start.territories.clone() } else { None };
    cv.geodesic = geodesic;
    let edges = match (&cv.geodesic, spec.edge_refinement) {
        (Some(g), Some(true)) => Some(g.field.clone()),
        _ => None,
    };
    Ok((ProblemKind::ChanVese(cv), None, edges, edge_contrast))
}

/// Default `problem.min_size`: 16 pixels (a disc of radius 2.3), 64 voxels.
pub fn default_min_size(d: usize) -> f64 {
    if d == 2 {
        16.0
    } else {
        64.0
    }
}
