//! A mesh of either dimension: a closed curve in the plane or a closed surface.

use super::{CurveMesh, SurfaceMesh};

/// A curve (2D) or a surface (3D) mesh, as initial shapes and mesh files give them.
#[derive(Debug, Clone, PartialEq)]
pub enum AnyMesh {
    Curve(CurveMesh),
    Surface(SurfaceMesh),
}

impl AnyMesh {
    pub fn dimension(&self) -> usize {
        match self {
            AnyMesh::Curve(_) => 2,
            AnyMesh::Surface(_) => 3,
        }
    }
}
