//! Building a stressed-film job from its spec: the cell, the boundary data and the
//! initial film surface (which needs the cell width `L`).

use super::checks::{finite, positive};
use crate::geometry::{CurveMesh, MeshError, Point};
use crate::jobs::spec::{
    ConstantBoundary, FilmBoundarySpec, FilmPolylineShape, FilmShape, InitialSpec, LinearBoundary, SpecError,
    StressedFilmSpec, XBoundary,
};
use crate::problems::{cosine_film, polyline_film, BoundaryData, FilmCell};

/// Most vertices of an initial film surface.
use crate::jobs::spec::bounds::FILM_RESOLUTION;

/// The cell of a spec (`problem.length`, `problem.boundary`).
pub fn film_cell(spec: &StressedFilmSpec) -> Result<FilmCell, SpecError> {
    let length = positive("problem.length", spec.length)?;
    positive("problem.gamma", spec.gamma)?;
    let boundary = match spec.boundary {
        FilmBoundarySpec::X(XBoundary {}) => BoundaryData::x(),
        FilmBoundarySpec::Constant(ConstantBoundary { value }) => {
            finite("problem.boundary.value", &[value])?;
            BoundaryData::constant(value)
        }
        FilmBoundarySpec::Linear(LinearBoundary { a, b, c }) => {
            finite("problem.boundary", &[a, b, c])?;
            BoundaryData { a, b, c }
        }
    };
    Ok(FilmCell { length, boundary })
}

fn mesh_err(field: &str, e: MeshError) -> SpecError {
    SpecError::new(field, format!("invalid film surface: {e}"))
}

/// The initial film surface: `initial` must be a `film` or a `film_polyline`.
pub fn initial_film(cell: &FilmCell, initial: Option<&InitialSpec>) -> Result<CurveMesh, SpecError> {
    let l = cell.length;
    match initial {
        None => Err(SpecError::new("initial", "missing field `initial` (shape `film` or `film_polyline`)")),
        Some(InitialSpec::Film(FilmShape { height, amplitude, mode, resolution })) => {
            let h = positive("initial.height", *height)?;
            finite("initial.amplitude", &[*amplitude])?;
            if amplitude.abs() >= h {
                return Err(SpecError::new("initial.amplitude", format!("must be below the height {h} in size")));
            }
            FILM_RESOLUTION.check("initial.resolution", *resolution)?;
            if *mode == 0 || 4 * *mode as usize > *resolution {
                return Err(SpecError::new("initial.mode", "must be at least 1 and at most resolution / 4"));
            }
            cosine_film(l, h, *amplitude, *mode, *resolution).map_err(|e| mesh_err("initial", e))
        }
        Some(InitialSpec::FilmPolyline(FilmPolylineShape { points, resolution })) => {
            if points.len() < 3 {
                return Err(SpecError::new("initial.points", format!("needs at least 3 points, got {}", points.len())));
            }
            for (i, p) in points.iter().enumerate() {
                finite(&format!("initial.points[{i}]"), p)?;
                if !(p[0] >= 0.0 && p[0] < l && p[1] > 0.0) {
                    return Err(SpecError::new(
                        format!("initial.points[{i}]"),
                        format!("must lie in the cell 0 ≤ x < {l}, y > 0"),
                    ));
                }
            }
            let pts: Vec<Point<2>> = points.iter().map(|p| Point::<2>::new(p[0], p[1])).collect();
            let pts = match resolution {
                None => pts,
                Some(n) => resample(&pts, l, FILM_RESOLUTION.check("initial.resolution", *n)?),
            };
            polyline_film(l, &pts).map_err(|e| mesh_err("initial.points", e))
        }
        Some(_) => Err(SpecError::new("initial.shape", "the stressed film needs `film` or `film_polyline`")),
    }
}

/// `n` points equally spaced in arclength along the periodic polyline.
fn resample(points: &[Point<2>], l: f64, n: usize) -> Vec<Point<2>> {
    let m = points.len();
    let at = |k: usize| if k < m { points[k] } else { points[k - m] + Point::<2>::new(l, 0.0) };
    let lengths: Vec<f64> = (0..m).map(|k| (at(k + 1) - at(k)).norm()).collect();
    let total: f64 = lengths.iter().sum();
    let mut out = Vec::with_capacity(n);
    let (mut k, mut start) = (0, 0.0);
    for i in 0..n {
        let s = total * i as f64 / n as f64;
        while k + 1 < m && start + lengths[k] < s {
            start += lengths[k];
            k += 1;
        }
        let t = ((s - start) / lengths[k].max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
        let mut p = at(k) + (at(k + 1) - at(k)) * t;
        p.x = p.x.rem_euclid(l);
        out.push(p);
    }
    out
}
