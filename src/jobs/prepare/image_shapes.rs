//! Initial shapes from an image: contours of a threshold (one per object, touching
//! objects split, dim objects found at a second threshold), a grid of seeds, and
//! the circle or sphere inscribed in the image box.

use super::checks::{curve, positive, surface};
use crate::geometry::AnyMesh;
use crate::geometry::{self, Mesh, Point};
pub(super) use crate::imaging::labels::RegionWeights;
use crate::imaging::labels::{
    clean_mask, components, distance_transform, reopen_holes, separate, split_at_peaks, split_at_ridges,
};
use crate::imaging::{contours, isosurface, Grid};
use crate::jobs::necks::NECKS;
use crate::jobs::spec::SpecError;

/// Holes of less than this fraction of the object around them are filled in the
/// initial shape (the flow does not open new holes) unless their samples fit the
/// background better than the object by more than the length of their boundary
/// costs ([`reopen_holes`]): objects in photographs and micrographs are mostly
/// solid, with darker details inside; a ring keeps its hole.
const HOLE_FRACTION: f64 = 0.25;

/// The thresholds of the automatic initial shape.
pub(super) struct Levels {
    pub main: f64,
    /// The permissive threshold of dim objects, if any.
    pub dim: Option<f64>,
    /// +1 for bright objects, −1 for dark ones.
    pub sign: f64,
}

impl Levels {
    pub fn polarity(&self) -> crate::jobs::spec::Polarity {
        if self.sign > 0.0 {
            crate::jobs::spec::Polarity::Bright
        } else {
            crate::jobs::spec::Polarity::Dark
        }
    }

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

/// How the initial shape splits touching objects (`problem.split_touching`,
/// `problem.min_separation`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum TouchingSplit {
    /// Each component of the threshold is one object.
    None,
    /// At necks ([`NECKS`]).
    Necks,
    /// At every maximum of the distance transform this far (samples) from every
    /// higher one of its component ([`split_at_peaks`]).
    Peaks(f64),
}

/// The main threshold with specks dropped and small holes filled, touching objects
/// split (`split`), and the filled holes reopened that fit `data` outside the objects
/// better, by the region energy of `weights`; then the components of the dim
/// threshold that contain no sample of the main mask (dim objects the main
/// threshold misses entirely) as objects of their own; one sample of background
/// between objects.
pub(super) fn threshold_objects(
    s: &Grid,
    data: &Grid,
    weights: RegionWeights,
    levels: &Levels,
    min_size: f64,
    split: TouchingSplit,
) -> ThresholdObjects {
    let min = min_size.ceil() as usize;
    let main: Vec<bool> = s.values.iter().map(|&v| levels.inside(v, levels.main)).collect();
    let bare = clean_mask(&main, s.dims, min, 0.0);
    let main = clean_mask(&main, s.dims, min, HOLE_FRACTION);
    let dist = || distance_transform(&main, s.dims, [1.0; 3]);
    let (mut labels, mut count) = match split {
        // the cut along the ridge of each neck, not around the smaller side's outer layers
        TouchingSplit::Necks => split_at_ridges(&main, &dist(), s.dims, &NECKS),
        TouchingSplit::Peaks(separation) => split_at_peaks(&main, &dist(), s.dims, separation, min),
        TouchingSplit::None => components(&main, s.dims),
    };
    // the holes are reopened after the split, which judges the objects whole
    let main = reopen_holes(&main, &bare, s.dims, &data.values, weights);
    for (l, &m) in labels.iter_mut().zip(&main) {
        if !m {
            *l = 0;
        }
    }
    let mut object_levels = vec![levels.main; count + 1];
    if let Some(t) = levels.dim {
        let dim: Vec<bool> = s.values.iter().map(|&v| levels.inside(v, t)).collect();
        let dim = clean_mask(&dim, s.dims, min, HOLE_FRACTION);
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

/// One closed curve (surface) per object and hole (cavity) of `objects`, on its
/// threshold level of the smoothed image (sub-sample) within each object's samples:
/// marching squares in 2D, marching tetrahedra in 3D. Returns the mesh and the
/// number of objects, `None` if there is no object.
pub(super) fn threshold_mesh(s: &Grid, objects: &ThresholdObjects) -> Result<Option<(AnyMesh, usize)>, SpecError> {
    let [nx, ny, nz] = s.dims;
    let mut bbox = vec![[usize::MAX, 0, usize::MAX, 0, usize::MAX, 0]; objects.count + 1];
    for (p, &lab) in objects.labels.iter().enumerate() {
        if lab != 0 {
            let b = &mut bbox[lab as usize];
            let (i, j, k) = (p % nx, (p / nx) % ny, p / (nx * ny));
            *b = [b[0].min(i), b[1].max(i + 1), b[2].min(j), b[3].max(j + 1), b[4].min(k), b[5].max(k + 1)];
        }
    }
    let l = s.scale();
    let unit = |x: f64| (x + 0.5) / l;
    let (mut loops, mut positions, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    let mut count = 0;
    for (lab, b) in bbox.iter().enumerate().skip(1) {
        if b[0] == usize::MAX {
            continue;
        }
        let t = objects.levels[lab];
        let grow = |lo: usize, hi: usize, n: usize| (lo.saturating_sub(1), (hi + 1).min(n));
        let ((i0, i1), (j0, j1), (k0, k1)) = (grow(b[0], b[1], nx), grow(b[2], b[3], ny), grow(b[4], b[5], nz));
        let depth = |p: usize| (objects.sign * (s.values[p] - t)).abs().max(1e-3);
        // in 3D another object's samples lie three times the deepest sample of the
        // window below the level: the surfaces of two objects whose samples are
        // corners of one cell (diagonal neighbours, one cleared sample between
        // them) cross the diagonal a quarter of it from their own sample each,
        // instead of at one point
        let deepest = if s.dimension == 3 {
            let samples =
                (k0..k1).flat_map(|k| (j0..j1).flat_map(move |j| (i0..i1).map(move |i| i + nx * (j + ny * k))));
            samples.map(depth).fold(0.0, f64::max)
        } else {
            0.0
        };
        let level = |i: usize, j: usize, k: usize| {
            let p = i + nx * (j + ny * k);
            match objects.labels[p] {
                l if l == lab as u32 => depth(p),
                l if l != 0 && s.dimension == 3 => -3.0 * deepest,
                _ => -depth(p),
            }
        };
        if s.dimension == 2 {
            let polys = contours::zero_level([i0, i1, j0, j1], |i, j| level(i, j, 0));
            count += !polys.is_empty() as usize;
            loops.extend(
                polys
                    .into_iter()
                    .filter_map(|poly| contours::polygon_loop(poly, l, |q| Point::<2>::new(unit(q[0]), unit(q[1])))),
            );
        } else {
            let (v, tris) = isosurface::zero_level_3d([i0, i1, j0, j1, k0, k1], level);
            count += !tris.is_empty() as usize;
            let offset = positions.len();
            positions.extend(v.iter().map(|q| Point::<3>::new(unit(q[0]), unit(q[1]), unit(q[2]))));
            triangles.extend(tris.iter().map(|t| t.map(|q| q + offset)));
        }
    }
    if s.dimension == 2 {
        if loops.is_empty() {
            return Ok(None);
        }
        let m =
            geometry::curves_from_loops(loops).map_err(|e| SpecError::new("initial", format!("invalid shape: {e}")))?;
        Ok(Some((AnyMesh::Curve(m), count)))
    } else {
        if triangles.is_empty() {
            return Ok(None);
        }
        let m =
            Mesh::new(positions, triangles).map_err(|e| SpecError::new("initial", format!("invalid shape: {e}")))?;
        Ok(Some((AnyMesh::Surface(m), count)))
    }
}

/// A grid of small circles (spheres) over the image box.
pub(super) fn seeds(grid: &Grid, spacing: Option<f64>, radius: Option<f64>) -> Result<AnyMesh, SpecError> {
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
        surface("initial", geometry::surface_union(&parts))
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
