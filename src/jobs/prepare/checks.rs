//! Value checks that name the failing field, shared by the preparation of every
//! problem.

use crate::geometry::{AnyMesh, CurveMesh, MeshError, SurfaceMesh};
use crate::jobs::spec::SpecError;

pub(super) fn positive(field: &str, v: f64) -> Result<f64, SpecError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SpecError::new(field, format!("must be a positive number, got {v}")))
    }
}

pub(super) fn finite(field: &str, v: &[f64]) -> Result<(), SpecError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(SpecError::new(format!("{field}[{i}]"), "must be a finite number")),
        None => Ok(()),
    }
}

pub(super) fn mesh_err(field: &str, e: MeshError) -> SpecError {
    SpecError::new(field, format!("invalid shape: {e}"))
}

pub(super) fn curve(field: &str, m: Result<CurveMesh, MeshError>) -> Result<AnyMesh, SpecError> {
    m.map(AnyMesh::Curve).map_err(|e| mesh_err(field, e))
}

pub(super) fn surface(field: &str, m: Result<SurfaceMesh, MeshError>) -> Result<AnyMesh, SpecError> {
    m.map(AnyMesh::Surface).map_err(|e| mesh_err(field, e))
}
