//! Checkpoints as plain data: everything the driver needs to continue a run exactly
//! as the uninterrupted run would.

use super::report::SurgeryRecord;
use crate::geometry::{Mesh, MeshError, Point};
use serde::{Deserialize, Serialize};

/// A mesh as plain data (for checkpoints and storage).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshData {
    pub dimension: usize,
    pub positions: Vec<Vec<f64>>,
    pub elements: Vec<Vec<usize>>,
    /// The period in `x` of a periodic curve (see [`Mesh::new_periodic`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period: Option<f64>,
}

impl<const D: usize> From<&Mesh<D>> for MeshData {
    fn from(m: &Mesh<D>) -> Self {
        MeshData {
            dimension: D,
            positions: m.positions().iter().map(|p| p.iter().copied().collect()).collect(),
            elements: m.elements().iter().map(|e| e.to_vec()).collect(),
            period: m.period(),
        }
    }
}

impl MeshData {
    /// The mesh of dimension `D` as it is, without validation (for reading off
    /// results of any state); `None` if the data are not of dimension `D`.
    pub fn to_mesh_unvalidated<const D: usize>(&self) -> Option<Mesh<D>> {
        let n = self.positions.len();
        if self.dimension != D
            || self.positions.iter().any(|p| p.len() != D)
            || self.elements.iter().any(|e| e.len() != D || e.iter().any(|&v| v >= n))
        {
            return None;
        }
        if let Some(period) = self.period {
            // a periodic curve (D = 2; for another D the downcast says no)
            let points = self.positions.iter().map(|p| Point::<2>::new(p[0], p[1])).collect();
            let segments = self.elements.iter().map(|e| [e[0], e[1]]).collect();
            return of_dimension(Mesh::<2>::periodic_trusted(points, segments, period));
        }
        let positions = self.positions.iter().map(|p| Point::<D>::from_iterator(p.iter().copied())).collect();
        let elements = self.elements.iter().map(|e| std::array::from_fn(|k| e[k])).collect();
        Some(Mesh::from_trusted_parts(positions, elements))
    }

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
        match self.period {
            None => Mesh::new(positions, elements),
            Some(period) => {
                let to_2d = |p: Point<D>| Point::<2>::new(p[0], p.get(1).copied().unwrap_or(f64::NAN));
                let segments = elements.iter().map(|e| [e[0], e.get(1).copied().unwrap_or(usize::MAX)]).collect();
                let curve = Mesh::<2>::new_periodic(positions.into_iter().map(to_2d).collect(), segments, period)?;
                of_dimension(curve).ok_or(MeshError::BadPeriod { period })
            }
        }
    }
}

/// A periodic curve as a mesh of dimension `D`: itself if `D` is 2.
fn of_dimension<const D: usize>(curve: Mesh<2>) -> Option<Mesh<D>> {
    let any: Box<dyn std::any::Any> = Box::new(curve);
    any.downcast::<Mesh<D>>().ok().map(|m| *m)
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
    /// The stage of a job with several (segmentation: 1 once the run continues with
    /// `lambda_final`); 0 for the first, and left out of the JSON then.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub stage: usize,
    /// The state is of a job's coarse start (segmentation of a volume: the surface
    /// converges on coarse edges first, then on the default ones); left out of the
    /// JSON when false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub coarse: bool,
    /// The `τ` of the last step that the flow's own limits set, which decides
    /// whether a step doubling back after a short one is judged for convergence
    /// ([`Flow`](super::Flow)); 0 (none yet) is left out of the JSON.
    #[serde(default, skip_serializing_if = "is_zero_f64")]
    pub settled_tau: f64,
    /// The recorded energies at the ends of the last judged steps, oldest first
    /// (the convergence test over several steps, [`Flow`](super::Flow)); left out
    /// of the JSON when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub recent_energies: Vec<f64>,
    /// The topological surgeries of the run so far, oldest first; left out of the
    /// JSON when there were none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub surgeries: Vec<SurgeryRecord>,
}

impl Checkpoint {
    /// This state, to be gone on from with the step `tau` as a new run would: the
    /// step size, the settled step and the energies of the convergence test of the
    /// run before it are dropped (a coarse start's end, a split at necks).
    pub fn with_fresh_step(self, tau: f64) -> Checkpoint {
        Checkpoint { tau, settled_tau: 0.0, recent_energies: Vec::new(), ..self }
    }
}

fn is_zero(s: &usize) -> bool {
    *s == 0
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn is_zero_f64(x: &f64) -> bool {
    *x == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A periodic curve (a film's surface over one period) read back with and
    /// without validation keeps its period and its vertices.
    #[test]
    fn a_periodic_curve_keeps_its_period() {
        let n = 8;
        let points: Vec<Point<2>> = (0..n)
            .map(|i| Point::<2>::new(i as f64 / n as f64, 0.5 + 0.1 * (6.0 * i as f64 / n as f64).sin()))
            .collect();
        let curve = Mesh::<2>::new_periodic(points, (0..n).map(|i| [i, (i + 1) % n]).collect(), 1.0).unwrap();
        let data = MeshData::from(&curve);
        let trusted = data.to_mesh_unvalidated::<2>().unwrap();
        let validated = data.to_mesh::<2>().unwrap();
        for m in [&trusted, &validated] {
            assert_eq!(m.period(), Some(1.0));
            assert_eq!(m.positions(), curve.positions());
        }
        assert!(data.to_mesh_unvalidated::<3>().is_none());
    }
}
