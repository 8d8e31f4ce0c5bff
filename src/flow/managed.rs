//! Mesh management after an accepted step (paper §4.1), as the driver applies it:
//! the manager's pass, the energy re-evaluated on its result, the pattern and the
//! symbolic factorizations rebuilt on a new connectivity.

use super::driver::Flow;
use super::mesh_management::Managed;
use super::report::StopReason;
use super::FlowError;
use crate::fem::Pattern;

impl<const D: usize> Flow<'_, D> {
    /// Apply the mesh manager, if any; a new connectivity rebuilds the pattern and
    /// drops the symbolic factorizations. The energy is re-evaluated on the result.
    /// Returns the stop the management calls for (`pinch_off`, `vanished`), if any.
    pub(super) fn manage_mesh(&mut self) -> Result<Option<StopReason>, FlowError> {
        let Some(manager) = self.manager.as_mut() else { return Ok(None) };
        let (mesh, remeshed) = match manager.manage(&self.mesh)? {
            Managed::Unchanged => return Ok(None),
            Managed::PinchOff => return Ok(Some(StopReason::PinchOff)),
            Managed::Vanished => return Ok(Some(StopReason::Vanished)),
            Managed::Moved(m) => (m, false),
            Managed::Remeshed(m) => (m, true),
        };
        let energy = self.problem.energy(&mesh).map_err(|e| FlowError::Problem(e.0))?;
        if energy == f64::INFINITY {
            // management made the shape inadmissible (shape design: a regularized
            // spike crossed a fixed boundary): keep the accepted mesh this time
            return Ok(None);
        }
        if !energy.is_finite() {
            return Err(FlowError::NonFiniteEnergy { value: energy, iteration: self.iteration });
        }
        self.mesh = mesh;
        if remeshed {
            self.pattern = Pattern::new(self.mesh.num_vertices(), self.mesh.elements());
            self.solver.reset();
        }
        self.energy = energy;
        Ok(None)
    }
}
