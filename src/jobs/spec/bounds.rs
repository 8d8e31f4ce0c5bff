//! The intervals of accepted values of the spec's numbers, stated once: the
//! schema's `minimum`/`maximum` (the `#[schemars(range(...))]` attributes of the
//! spec types) and the checks of `prepare` both read them from here.

use super::SpecError;
use crate::limits::{MAX_FILM_VERTICES, MAX_VERTICES};
use std::fmt::Display;

/// A closed interval `[min, max]` of accepted values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound<T> {
    pub min: T,
    pub max: T,
}

impl<T: PartialOrd + Display + Copy> Bound<T> {
    /// `v` if it lies in the interval; else an error on `field` that states the
    /// interval.
    pub fn check(&self, field: &str, v: T) -> Result<T, SpecError> {
        if v >= self.min && v <= self.max {
            Ok(v)
        } else {
            Err(SpecError::new(field, format!("must be between {} and {}, got {v}", self.min, self.max)))
        }
    }
}

/// `resolution` of a curve shape: its number of vertices.
pub const CURVE_RESOLUTION: Bound<usize> = Bound { min: 3, max: MAX_VERTICES };
/// `resolution` of a film surface: its number of vertices.
pub const FILM_RESOLUTION: Bound<usize> = Bound { min: 8, max: MAX_FILM_VERTICES };
/// `resolution` of a sphere or an ellipsoid: the icosphere's subdivision level.
pub const SPHERE_LEVEL: Bound<u32> = Bound { min: 0, max: 8 };
/// `resolution` of a torus: segments around its axis.
pub const TORUS_RESOLUTION: Bound<usize> = Bound { min: 3, max: 4096 };
/// `flow.max_iterations`.
pub const MAX_ITERATIONS: Bound<usize> = Bound { min: 1, max: 100_000_000 };
/// `mesh.sweeps`: regularization sweeps per step.
pub const SWEEPS: Bound<usize> = Bound { min: 0, max: 1000 };
/// `problem.channel` of segmentation.
pub const CHANNEL: Bound<u32> = Bound { min: 0, max: 255 };
/// `problem.time_point` of segmentation.
pub const TIME_POINT: Bound<u32> = Bound { min: 0, max: 1_000_000 };
/// `mesh.max_angle` (degrees).
pub const MAX_ANGLE: Bound<f64> = Bound { min: 90.0, max: 179.0 };
/// `problem.sigma` and `problem.data_sigma` of a segmentation (pixels).
pub const SIGMA: Bound<f64> = Bound { min: 0.0, max: 64.0 };
/// The weights of a segmentation: `mu`, `lambda_in`, `lambda_out`, and the
/// contrast scale `edge_contrast` (which must also be positive).
pub const WEIGHT: Bound<f64> = Bound { min: 0.0, max: 1000.0 };
/// `problem.threshold` and `problem.dim_threshold` (the normalized scale).
pub const LEVEL: Bound<f64> = Bound { min: 0.0, max: 1.0 };
/// `problem.percentiles`.
pub const PERCENTILE: Bound<f64> = Bound { min: 0.0, max: 100.0 };
/// `problem.min_size` (pixels or voxels).
pub const MIN_SIZE: Bound<f64> = Bound { min: 0.0, max: 1e9 };
/// `problem.min_separation` (pixels or voxels).
pub const MIN_SEPARATION: Bound<f64> = Bound { min: 1.0, max: 1e4 };

#[cfg(test)]
mod tests {
    use super::*;

    /// Both ends are accepted; a value outside is an error on the field that
    /// states the interval.
    #[test]
    fn a_bound_is_closed_and_its_error_names_the_field() {
        assert_eq!(SIGMA.check("problem.sigma", 0.0), Ok(0.0));
        assert_eq!(SIGMA.check("problem.sigma", 64.0), Ok(64.0));
        let e = SIGMA.check("problem.sigma", 64.5).unwrap_err();
        assert_eq!(e.field, "problem.sigma");
        assert_eq!(e.message, "must be between 0 and 64, got 64.5");
        assert!(CURVE_RESOLUTION.check("initial.resolution", 2).is_err());
        assert_eq!(CURVE_RESOLUTION.max, crate::limits::MAX_VERTICES);
    }
}
