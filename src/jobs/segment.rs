//! A segmentation job from its spec: the image's automatic settings (percentile
//! normalization, noise level, smoothing, polarity, threshold), the automatic
//! initial shape (threshold contours, seeds, or the inscribed circle/sphere) and
//! the functional (Chan–Vese, geodesic, or both). Every automatic choice is kept
//! in a [`SegmentationSetup`] that the results report.

use super::build::{curve, in_range, load_image, positive, surface, AnyMesh, ProblemKind};
use super::spec::{
    BackgroundModel, ImageSource, InitialSpec, MeansKind, Polarity, SegmentationModel, SegmentationSpec, SpecError,
};
use crate::geometry::{self, Point};
use crate::imaging::labels::{clean_mask, components, distance_transform, separate, split_touching};
use crate::imaging::{
    contours, gaussian_smooth, histogram_mode, noise_level, otsu, quadratic_background, smoothed_noise,
    smoothing_for_noise, EdgeField, Grid, Normalization, PERCENTILES,
};
use crate::problems::{ChanVese, Segmentation};
use serde::Serialize;
use std::collections::HashMap;
use std::sync::Arc;

/// Default `problem.mu` (intensity² × pixels).
pub const DEFAULT_MU: f64 = 0.05;
/// Relative depth of a neck that splits touching objects (see [`split_touching`]).
const SPLIT_RELATIVE_DEPTH: f64 = 0.0;
/// Absolute depth (pixels) of a neck that splits touching objects.
const SPLIT_DEPTH: f64 = 1.5;
/// Dim objects are detected this many standard deviations of the smoothed noise
/// away from the background level.
const DIM_OBJECT_SNR: f64 = 8.0;

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
    /// Gaussian smoothing (pixels).
    pub sigma: f64,
    pub background: BackgroundModel,
    /// The range (largest minus smallest value) of the illumination removed.
    pub illumination_range: f64,
    pub polarity: Polarity,
    /// Threshold of the automatic initial shape (normalized scale).
    pub threshold: f64,
    /// The more permissive threshold for dim objects that the main one misses
    /// entirely (`None` where it is not more permissive).
    pub dim_threshold: Option<f64>,
    pub min_size: f64,
    /// Objects of the initial shape.
    pub initial_objects: usize,
    pub mu: f64,
    pub lambda_in: f64,
    pub lambda_out: f64,
    pub means: MeansKind,
    pub merge: bool,
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
}

pub(super) fn prepare_segmentation(
    spec: &SegmentationSpec,
    initial: Option<&InitialSpec>,
    inputs: &HashMap<String, Vec<u8>>,
) -> Result<PreparedSegmentation, SpecError> {
    let grid = load_image(&spec.image, inputs)?;
    let (d, l) = (grid.dimension, grid.scale());
    let percentiles = spec.percentiles.unwrap_or([PERCENTILES.0, PERCENTILES.1]);
    in_range("problem.percentiles[0]", percentiles[0], 0.0, 100.0)?;
    in_range("problem.percentiles[1]", percentiles[1], 0.0, 100.0)?;
    if percentiles[0] >= percentiles[1] {
        return Err(SpecError::new("problem.percentiles", "the first must be below the second"));
    }
    let constant = || {
        let names = match &spec.image {
            ImageSource::One(s) => s.clone(),
            ImageSource::Slices(v) => v.join(", "),
        };
        SpecError::new("problem.image", format!("the image {names} is constant: there is nothing to segment"))
    };
    let norm = Normalization::of(&grid, (percentiles[0], percentiles[1])).ok_or_else(constant)?;
    let unit = norm.apply(&grid);
    let noise = noise_level(&unit);
    let model = spec.model.unwrap_or(if d == 2 { SegmentationModel::ChanVese } else { SegmentationModel::Geodesic });
    let sigma = match spec.sigma {
        Some(s) => {
            if !(s.is_finite() && (0.0..=64.0).contains(&s)) {
                return Err(SpecError::new("problem.sigma", format!("must be between 0 and 64 pixels, got {s}")));
            }
            s
        }
        None if model == SegmentationModel::ChanVese => smoothing_for_noise(noise, d),
        // the edge indicator's own default, raised for noisy images
        None => smoothing_for_noise(noise, d).max(super::spec::default_sigma(d)),
    };
    let smoothed = gaussian_smooth(&unit, sigma);
    let first = otsu(&smoothed.values).ok_or_else(constant)?;
    let polarity = spec.polarity.unwrap_or_else(|| border_polarity(&smoothed, first));
    let background_model = spec.background.unwrap_or(BackgroundModel::Quadratic);
    let (smoothed, illumination) = match background_model {
        BackgroundModel::Flat => (smoothed, 0.0),
        BackgroundModel::Quadratic => flatten(smoothed, first, polarity),
    };
    let threshold = match spec.threshold {
        Some(t) => in_range("problem.threshold", t, 0.0, 1.0)?,
        None => otsu(&smoothed.values).ok_or_else(constant)?,
    };
    // dim objects: above the background level by DIM_OBJECT_SNR times the smoothed
    // noise (a threshold only where it is more permissive than the main one)
    let sign = if polarity == Polarity::Bright { 1.0 } else { -1.0 };
    let dim_threshold = match spec.dim_threshold {
        Some(t) => in_range("problem.dim_threshold", t, 0.0, 1.0)?,
        None => {
            let background = histogram_mode(&smoothed.values);
            (background + sign * DIM_OBJECT_SNR * smoothed_noise(noise, sigma, d)).clamp(0.0, 1.0)
        }
    };
    let dim_threshold = (sign * (threshold - dim_threshold) > 0.0).then_some(dim_threshold);
    let min_size = match spec.min_size {
        Some(m) => in_range("problem.min_size", m, 0.0, 1e9)?,
        None => default_min_size(d),
    };
    let mu = in_range("problem.mu", spec.mu.unwrap_or(DEFAULT_MU), 0.0, 1000.0)?;
    let lambda_in = in_range("problem.lambda_in", spec.lambda_in.unwrap_or(1.0), 0.0, 1000.0)?;
    let lambda_out = in_range("problem.lambda_out", spec.lambda_out.unwrap_or(1.0), 0.0, 1000.0)?;
    // the geodesic model's weights are checked whichever model runs
    for (field, v) in [("problem.lambda", spec.lambda), ("problem.lambda_final", spec.lambda_final)] {
        if let Some(v) = v.filter(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(SpecError::new(field, format!("must be a nonnegative number, got {v}")));
        }
    }
    if let Some(e) = spec.epsilon {
        positive("problem.epsilon", e)?;
    }
    let means = spec.means.unwrap_or(MeansKind::PerObject);
    let merge = spec.merge.unwrap_or(false);

    // the initial shape from the image, and the samples that separate its objects
    let image_shape = match initial {
        None if d == 2 => Some(InitialSpec::Threshold {}),
        None => Some(InitialSpec::Inscribed {}),
        Some(s @ (InitialSpec::Threshold {} | InitialSpec::Seeds { .. } | InitialSpec::Inscribed {})) => {
            Some(s.clone())
        }
        Some(_) => None,
    };
    let (mut mesh, mut cut, mut initial_objects) = (None, Vec::new(), 0);
    let mut background = None;
    match image_shape {
        Some(InitialSpec::Threshold {}) => {
            let levels = Levels { main: threshold, dim: dim_threshold, sign };
            let objects = threshold_objects(&smoothed, &levels, min_size, spec.split_touching.unwrap_or(true));
            let (m, count) = threshold_mesh(&smoothed, &objects)?;
            (mesh, cut, initial_objects, background) = (Some(m), objects.cleared, count, Some(objects.background));
        }
        Some(InitialSpec::Seeds { spacing, radius }) => {
            let m = seeds(&grid, spacing, radius)?;
            initial_objects = match &m {
                AnyMesh::Curve(c) => c.num_components(),
                AnyMesh::Surface(s) => s.num_components(),
            };
            mesh = Some(m);
        }
        Some(InitialSpec::Inscribed {}) => {
            mesh = Some(inscribed(&grid)?);
            initial_objects = 1;
        }
        _ => {}
    }

    let mut second_stage = None;
    let mut edges = None;
    // (the weights given in the spec are checked above)
    let geodesic = match model {
        SegmentationModel::ChanVese => None,
        _ => {
            let epsilon = spec.epsilon.unwrap_or(super::spec::default_beta_epsilon(l));
            let lambda = spec.lambda.unwrap_or(match model {
                SegmentationModel::Both => 0.0,
                _ => super::spec::default_lambda(d, l),
            });
            let field = EdgeField::new(&grid, sigma).ok_or_else(constant)?;
            Some(Segmentation { field: Arc::new(field), lambda, epsilon })
        }
    };
    let problem = match (model, geodesic) {
        (SegmentationModel::Geodesic, Some(problem)) => {
            let lambda_final = spec.lambda_final.unwrap_or(super::spec::default_lambda_final(d, problem.lambda));
            if lambda_final != problem.lambda {
                second_stage =
                    Some(ProblemKind::Segmentation(Segmentation { lambda: lambda_final, ..problem.clone() }));
            }
            if spec.edge_refinement.unwrap_or(true) {
                edges = Some(problem.field.clone());
            }
            ProblemKind::Segmentation(problem)
        }
        (_, geodesic) => {
            let mut values = smoothed.values.clone();
            if let Some(bg) = background {
                // the samples between touching objects get the background level, so
                // that their contours stay apart
                for &p in &cut {
                    values[p] = bg;
                }
            }
            let mut cv = ChanVese::new(d, grid.dims, &values, mu / l, (lambda_in, lambda_out));
            cv.per_object = means == MeansKind::PerObject;
            cv.separate = cv.per_object && !merge;
            cv.geodesic = geodesic;
            if spec.edge_refinement == Some(true) {
                if let Some(g) = &cv.geodesic {
                    edges = Some(g.field.clone());
                }
            }
            ProblemKind::ChanVese(cv)
        }
    };
    let setup = SegmentationSetup {
        model,
        percentiles,
        intensity_range: [norm.lo, norm.hi],
        noise,
        sigma,
        background: background_model,
        illumination_range: illumination,
        polarity,
        threshold,
        dim_threshold,
        min_size,
        initial_objects,
        mu,
        lambda_in,
        lambda_out,
        means,
        merge,
    };
    Ok(PreparedSegmentation { grid, problem, second_stage, edges, mesh, setup })
}

/// `smoothed` with a quadratic illumination removed (its mean over the background
/// kept), fitted to the samples outside the objects of Otsu's threshold, twice (the
/// second time with the threshold of the first corrected image); and the range of
/// the illumination removed. Unchanged where the fit is not possible.
fn flatten(smoothed: Grid, threshold: f64, polarity: Polarity) -> (Grid, f64) {
    let sign = if polarity == Polarity::Bright { 1.0 } else { -1.0 };
    let mut current = smoothed.clone();
    let mut t = threshold;
    let mut range = 0.0;
    for _ in 0..2 {
        let background: Vec<bool> = current.values.iter().map(|&v| sign * (v - t) <= 0.0).collect();
        let Some(b) = quadratic_background(&smoothed, &background) else { break };
        let (sum, n) =
            b.iter().zip(&background).filter(|(_, &m)| m).fold((0.0, 0.0), |(s, n), (v, _)| (s + v, n + 1.0));
        let mean = sum / n;
        let (lo, hi) = b.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, c), &v| (a.min(v), c.max(v)));
        range = hi - lo;
        current =
            Grid { values: smoothed.values.iter().zip(&b).map(|(v, b)| v - b + mean).collect(), ..smoothed.clone() };
        match otsu(&current.values) {
            Some(next) => t = next,
            None => break,
        }
    }
    (current, range)
}

/// Default `problem.min_size`: 16 pixels (a disc of radius 2.3), 64 voxels.
pub fn default_min_size(d: usize) -> f64 {
    if d == 2 {
        16.0
    } else {
        64.0
    }
}

/// `Bright` unless most of the image's border lies above the threshold.
fn border_polarity(g: &Grid, t: f64) -> Polarity {
    let [nx, ny, nz] = g.dims;
    let (mut above, mut total) = (0usize, 0usize);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let border = i == 0 || j == 0 || i + 1 == nx || j + 1 == ny || (nz > 1 && (k == 0 || k + 1 == nz));
                if border {
                    total += 1;
                    above += (g.values[g.index(i, j, k)] > t) as usize;
                }
            }
        }
    }
    if 2 * above > total {
        Polarity::Dark
    } else {
        Polarity::Bright
    }
}

/// The thresholds of the automatic initial shape.
struct Levels {
    main: f64,
    /// The permissive threshold of dim objects, if any.
    dim: Option<f64>,
    /// +1 for bright objects, −1 for dark ones.
    sign: f64,
}

impl Levels {
    fn inside(&self, v: f64, t: f64) -> bool {
        self.sign * (v - t) > 0.0
    }
}

/// The objects of a thresholded image.
pub(super) struct ThresholdObjects {
    /// Label per sample (`1..=count`, 0 background).
    pub labels: Vec<u32>,
    pub count: usize,
    /// The threshold each label's contour is drawn at (index = label).
    pub levels: Vec<f64>,
    pub sign: f64,
    /// Samples cleared between touching objects.
    pub cleared: Vec<usize>,
    /// Mean of the smoothed image over the background.
    pub background: f64,
}

/// The main threshold with specks dropped and small holes filled, touching objects
/// split; then the components of the dim threshold that contain no sample of the
/// main mask (dim objects the main threshold misses entirely) as objects of their
/// own; one sample of background between objects.
fn threshold_objects(s: &Grid, levels: &Levels, min_size: f64, split: bool) -> ThresholdObjects {
    let min = min_size.ceil() as usize;
    let main: Vec<bool> = s.values.iter().map(|&v| levels.inside(v, levels.main)).collect();
    let main = clean_mask(&main, s.dims, min);
    let (mut labels, mut count) = if split {
        let dist = distance_transform(&main, s.dims, [1.0; 3]);
        split_touching(&main, &dist, s.dims, SPLIT_DEPTH, SPLIT_RELATIVE_DEPTH)
    } else {
        components(&main, s.dims)
    };
    let mut object_levels = vec![levels.main; count + 1];
    if let Some(t) = levels.dim {
        let dim: Vec<bool> = s.values.iter().map(|&v| levels.inside(v, t)).collect();
        let dim = clean_mask(&dim, s.dims, min);
        let (dim_labels, n) = components(&dim, s.dims);
        let mut touches_main = vec![false; n + 1];
        for (p, &l) in dim_labels.iter().enumerate() {
            touches_main[l as usize] |= main[p];
        }
        let mut new_label = vec![0u32; n + 1];
        for (p, &l) in dim_labels.iter().enumerate() {
            if l != 0 && !touches_main[l as usize] {
                if new_label[l as usize] == 0 {
                    count += 1;
                    new_label[l as usize] = count as u32;
                    object_levels.push(t);
                }
                labels[p] = new_label[l as usize];
            }
        }
    }
    let (bg_sum, bg_n) =
        s.values.iter().zip(&labels).filter(|(_, &l)| l == 0).fold((0.0, 0usize), |(a, n), (v, _)| (a + v, n + 1));
    let background = if bg_n > 0 { bg_sum / bg_n as f64 } else { 0.0 };
    let cleared = separate(&mut labels, s.dims);
    ThresholdObjects { labels, count, levels: object_levels, sign: levels.sign, cleared, background }
}

/// One closed curve per object and hole of `objects`, on its threshold level of the
/// smoothed image (sub-pixel) within each object's samples.
fn threshold_mesh(s: &Grid, objects: &ThresholdObjects) -> Result<(AnyMesh, usize), SpecError> {
    let none = || SpecError::new("initial", "the threshold finds no object in the image: give `initial` a shape");
    if s.dimension != 2 {
        return Err(SpecError::new(
            "initial.shape",
            "`threshold` is for 2D images; a volume starts from `inscribed`, `seeds` or a given surface",
        ));
    }
    let [nx, ny, _] = s.dims;
    let mut bbox = vec![[usize::MAX, 0, usize::MAX, 0]; objects.count + 1];
    for (p, &lab) in objects.labels.iter().enumerate() {
        if lab != 0 {
            let b = &mut bbox[lab as usize];
            let (i, j) = (p % nx, p / nx);
            *b = [b[0].min(i), b[1].max(i + 1), b[2].min(j), b[3].max(j + 1)];
        }
    }
    let l = s.scale();
    let mut loops = Vec::new();
    let mut count = 0;
    for (lab, b) in bbox.iter().enumerate().skip(1) {
        if b[0] == usize::MAX {
            continue;
        }
        let t = objects.levels[lab];
        let window = [b[0].saturating_sub(1), (b[1] + 1).min(nx), b[2].saturating_sub(1), (b[3] + 1).min(ny)];
        let level = |i: usize, j: usize| {
            let p = i + nx * j;
            let a = (objects.sign * (s.values[p] - t)).abs().max(1e-3);
            if objects.labels[p] == lab as u32 {
                a
            } else {
                -a
            }
        };
        let polys = contours::zero_level(window, level);
        if !polys.is_empty() {
            count += 1;
        }
        for poly in polys {
            let mut pts: Vec<Point<2>> = Vec::with_capacity(poly.len());
            for q in poly {
                let x = Point::<2>::new((q[0] + 0.5) / l, (q[1] + 0.5) / l);
                if pts.last().is_none_or(|p| (p - x).norm() * l > 0.1) {
                    pts.push(x);
                }
            }
            while pts.len() > 3 && (pts[0] - pts[pts.len() - 1]).norm() * l <= 0.1 {
                pts.pop();
            }
            if pts.len() >= 3 {
                loops.push(pts);
            }
        }
    }
    if loops.is_empty() {
        return Err(none());
    }
    let m = geometry::curves_from_loops(loops).map_err(|e| SpecError::new("initial", format!("invalid shape: {e}")))?;
    Ok((AnyMesh::Curve(m), count))
}

/// A grid of small circles (spheres) over the image box.
fn seeds(grid: &Grid, spacing: Option<f64>, radius: Option<f64>) -> Result<AnyMesh, SpecError> {
    let l = grid.scale();
    let used = &grid.dims[..grid.dimension];
    let shortest = used.iter().copied().min().unwrap_or(1) as f64;
    let spacing = match spacing {
        Some(s) => positive("initial.spacing", s)?,
        None => (shortest / 8.0).max(4.0),
    };
    let radius = match radius {
        Some(r) => positive("initial.radius", r)?,
        None => spacing / 4.0,
    };
    if 2.0 * radius >= spacing {
        return Err(SpecError::new("initial.radius", format!("must be below half of the spacing ({spacing} pixels)")));
    }
    let counts: Vec<usize> = used.iter().map(|&n| ((n as f64 / spacing).floor() as usize).max(1)).collect();
    let total: usize = counts.iter().product();
    if total > 100_000 {
        return Err(SpecError::new("initial.spacing", format!("makes {total} seeds; at most 100000")));
    }
    let centre = |a: usize, k: usize| {
        let n = grid.dims[a] as f64;
        (n - counts[a] as f64 * spacing) / 2.0 + (k as f64 + 0.5) * spacing
    };
    if grid.dimension == 2 {
        let mut parts = Vec::with_capacity(total);
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                let c = [centre(0, i) / l, centre(1, j) / l];
                parts.push(geometry::circle(c, radius / l, 16).map_err(|e| SpecError::new("initial", e.to_string()))?);
            }
        }
        curve("initial", geometry::union(&parts))
    } else {
        let mut parts = Vec::with_capacity(total);
        for k in 0..counts[2] {
            for j in 0..counts[1] {
                for i in 0..counts[0] {
                    let c = [centre(0, i) / l, centre(1, j) / l, centre(2, k) / l];
                    parts.push(
                        geometry::icosphere(c, radius / l, 1).map_err(|e| SpecError::new("initial", e.to_string()))?,
                    );
                }
            }
        }
        surface("initial", super::build::surface_union(&parts))
    }
}

/// A circle (sphere) inscribed in the image box, two pixels inside it, with
/// vertices `max(4, L/128)` pixels apart (an icosphere with edges of about three
/// pixels); adaptivity refines it where the contour bends.
pub(super) fn inscribed(grid: &Grid) -> Result<AnyMesh, SpecError> {
    let ext = grid.extent();
    let l = grid.scale();
    if grid.dimension == 2 {
        let r = 0.5 * ext[0].min(ext[1]) - 2.0 / l;
        let spacing = (l / 128.0).max(4.0);
        let n = ((std::f64::consts::TAU * r * l / spacing).round() as usize).clamp(32, 4096);
        curve("initial", geometry::circle([0.5 * ext[0], 0.5 * ext[1]], r, n))
    } else {
        let r = 0.5 * ext[0].min(ext[1]).min(ext[2]) - 2.0 / l;
        let level = (1.05 * r * l / 3.0).log2().round().clamp(1.0, 6.0) as u32;
        surface("initial", geometry::icosphere([0.5 * ext[0], 0.5 * ext[1], 0.5 * ext[2]], r, level))
    }
}
