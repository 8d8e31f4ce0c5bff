//! Checkpoints as plain data: everything the driver needs to continue a run exactly
//! as the uninterrupted run would.

use crate::geometry::{Mesh, MeshError, Point};
use serde::{Deserialize, Serialize};

/// A mesh as plain data (for checkpoints and storage).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshData {
    pub dimension: usize,
    pub positions: Vec<Vec<f64>>,
    pub elements: Vec<Vec<usize>>,
}

impl<const D: usize> From<&Mesh<D>> for MeshData {
    fn from(m: &Mesh<D>) -> Self {
        MeshData {
            dimension: D,
            positions: m.positions().iter().map(|p| p.iter().copied().collect()).collect(),
            elements: m.elements().iter().map(|e| e.to_vec()).collect(),
        }
    }
}

impl MeshData {
    /// Rebuild a validated mesh of dimension `D`.
    pub fn to_mesh<const D: usize>(&self) -> Result<Mesh<D>, MeshError> {
        let positions = self
            .positions
            .iter()
            .enumerate()
            .map(|(vertex, p)| {
                if p.len() != D || self.dimension != D {
                    return Err(MeshError::NonFinite { vertex });
                }
                Ok(Point::<D>::from_iterator(p.iter().copied()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let elements = self
            .elements
            .iter()
            .enumerate()
            .map(|(element, e)| <[usize; D]>::try_from(e.as_slice()).map_err(|_| MeshError::RepeatedVertex { element }))
            .collect::<Result<Vec<_>, _>>()?;
        Mesh::new(positions, elements)
    }
}

/// The driver state after an accepted step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub iteration: usize,
    pub time: f64,
    /// The last accepted time step (the next step tries `min(2τ, τ_spec)`).
    pub tau: f64,
    pub energy: f64,
    pub mesh: MeshData,
}
