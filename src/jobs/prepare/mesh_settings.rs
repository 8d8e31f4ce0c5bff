//! `mesh`: the mesh management of curves and surfaces, resolved from the spec and
//! the initial mesh.

use super::checks::positive;
use crate::flow::{CurveManager, SurfaceManager};
use crate::geometry::{CurveMesh, SurfaceMesh};
use crate::jobs::spec::bounds::{MAX_ANGLE, SWEEPS};
use crate::jobs::spec::{MeshSpec, SpecError};

/// `(ε, h_min, h_max)`: the spec's values where given, else the defaults; checked.
fn sizes(m: &MeshSpec, defaults: (f64, f64, f64)) -> Result<(f64, f64, f64), SpecError> {
    let epsilon = m.epsilon.map_or(Ok(defaults.0), |e| positive("mesh.epsilon", e))?;
    let h_min = m.h_min.map_or(Ok(defaults.1), |h| positive("mesh.h_min", h))?;
    let h_max = m.h_max.map_or(Ok(defaults.2), |h| positive("mesh.h_max", h))?;
    if h_min * 2.0 > h_max {
        return Err(SpecError::new("mesh.h_max", format!("must be at least twice mesh.h_min ({h_min})")));
    }
    Ok((epsilon, h_min, h_max))
}

pub(super) fn surface_manager(
    m: &MeshSpec,
    initial: &SurfaceMesh,
    pinch_off: bool,
) -> Result<Option<SurfaceManager>, SpecError> {
    if !(m.regularize || m.adapt || pinch_off) {
        return Ok(None);
    }
    let (mut params, _) = SurfaceManager::defaults_for(initial);
    (params.epsilon, params.h_min, params.h_max) = sizes(m, (params.epsilon, params.h_min, params.h_max))?;
    params.max_angle_deg = MAX_ANGLE.check("mesh.max_angle", m.max_angle)?;
    let sweeps = SWEEPS.check("mesh.sweeps", m.sweeps.unwrap_or(3))?;
    let pinch_curvature = pinch_off.then_some(2.0 / params.h_min);
    Ok(Some(SurfaceManager { regularize: m.regularize, sweeps, adapt: m.adapt, params, pinch_curvature }))
}

pub(super) fn curve_manager(m: &MeshSpec, initial: &CurveMesh) -> Result<Option<CurveManager>, SpecError> {
    if !(m.regularize || m.adapt || m.topology_changes) {
        return Ok(None);
    }
    let mut params = CurveManager::defaults_for(initial);
    (params.epsilon, params.h_min, params.h_max) = sizes(m, (params.epsilon, params.h_min, params.h_max))?;
    if let Some(a) = m.min_area {
        params.min_area = positive("mesh.min_area", a)?;
    }
    let sweeps = SWEEPS.check("mesh.sweeps", m.sweeps.unwrap_or(1))?;
    Ok(Some(CurveManager {
        regularize: m.regularize,
        sweeps,
        adapt: m.adapt,
        topology_changes: m.topology_changes,
        params,
    }))
}
