//! `mesh`: the mesh management of curves and surfaces, resolved from the spec and
//! the initial mesh.

use super::checks::positive;
use crate::flow::{CurveManager, FlowSettings, SurfaceManager, Surgery};
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

/// `(h_min, h_max)` of a surface traced from an image with voxels of length
/// `voxel`: edges kept between half a voxel and one voxel unless the spec sets
/// them. Coarser triangles no longer follow the detail the surface was traced
/// with, and the marching-tetrahedra slivers below a quarter voxel stall the steps
/// (on a brain MR, either made the energy rise at every management pass until `τ`
/// collapsed); edges of half a voxel and more take a third fewer steps to
/// convergence than a quarter on the nuclei volumes, each on fewer vertices, at
/// the same Dice (docs/segmentation-real-images.md). The one the spec gives
/// stays; the other keeps `h_max ≥ 2 h_min`.
fn traced_sizes(m: &MeshSpec, (h_min, h_max): (f64, f64), voxel: f64) -> (f64, f64) {
    match (m.h_min, m.h_max) {
        (None, None) => {
            let h_min = h_min.max(0.5 * voxel);
            (h_min, h_max.min(voxel).max(2.0 * h_min))
        }
        (Some(_), None) => (h_min, h_max.min(voxel).max(2.0 * h_min)),
        (None, Some(_)) => (h_min.max(0.5 * voxel).min(0.5 * h_max), h_max),
        (Some(_), Some(_)) => (h_min, h_max),
    }
}

/// The surface's management; `traced_voxel`, the voxel length of the image a
/// surface was traced from ([`traced_sizes`]).
pub(super) fn surface_manager(
    m: &MeshSpec,
    initial: &SurfaceMesh,
    pinch_off: bool,
    surgery: Option<Surgery>,
    traced_voxel: Option<f64>,
) -> Result<Option<SurfaceManager>, SpecError> {
    if !(m.regularize || m.adapt || pinch_off) {
        return Ok(None);
    }
    let (mut params, _) = SurfaceManager::defaults_for(initial);
    (params.epsilon, params.h_min, params.h_max) = sizes(m, (params.epsilon, params.h_min, params.h_max))?;
    if let Some(voxel) = traced_voxel {
        (params.h_min, params.h_max) = traced_sizes(m, (params.h_min, params.h_max), voxel);
    }
    params.max_angle_deg = MAX_ANGLE.check("mesh.max_angle", m.max_angle)?;
    let sweeps = SWEEPS.check("mesh.sweeps", m.sweeps.unwrap_or(3))?;
    // surgery: necks cut (detected as for the stop), and with `merge` surfaces in
    // contact joined
    let (pinch_curvature, surgery) = match (pinch_off, surgery) {
        (true, _) => (Some(2.0 / params.h_min), None),
        (false, Some(s)) => (Some(2.0 / params.h_min), Some(s)),
        (false, None) => (None, None),
    };
    Ok(Some(SurfaceManager {
        regularize: m.regularize,
        sweeps,
        adapt: m.adapt,
        params,
        pinch_curvature,
        surgery,
        declined: None,
    }))
}

/// The management of a coarse start ([`MeshSpec::coarse_start`]): a surface
/// traced from the image whose sizes the spec leaves to the defaults first
/// converges on longer edges ([`COARSE_H_MIN`], [`COARSE_H_MAX`] times the
/// default bounds: ¾ voxel to two voxels), on a quarter to a half of the
/// vertices, then goes on with `fine`. Off without adaptivity (the edges could
/// not be refined afterwards), without a tolerance or with an end time (the
/// coarse run would not end before the job does).
pub(super) fn coarse_manager(
    m: &MeshSpec,
    fine: Option<&SurfaceManager>,
    traced_voxel: Option<f64>,
    flow: &FlowSettings,
) -> Option<SurfaceManager> {
    let fine = fine.filter(|f| f.adapt)?;
    let traced = traced_voxel.is_some() && m.h_min.is_none() && m.h_max.is_none();
    let converges = flow.tolerance > 0.0 && flow.end_time.is_none();
    (m.coarse_start && traced && converges).then(|| {
        let mut coarse = *fine;
        coarse.params.h_min *= COARSE_H_MIN;
        coarse.params.h_max *= COARSE_H_MAX;
        coarse
    })
}

/// The coarse start's longest edge, in default longest edges: flat stretches of
/// the surface coarsen to two voxels.
const COARSE_H_MAX: f64 = 2.0;

/// The coarse start's shortest edge, in default shortest edges: ¾ voxel, so that
/// a curved patch keeps edges short enough to follow it. With one voxel (twice
/// the default) balls of radius 2–3.5 voxels ended 5–19 % smaller than without a
/// coarse start, and the default edges after it did not bring them back
/// (docs/segmentation-real-images.md).
const COARSE_H_MIN: f64 = 1.5;

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
