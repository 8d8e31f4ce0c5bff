//! Contact (paper §4.1, topological changes): a trial step in which two curves
//! cross ([`Problem::merges`]) and whose merged shape has a higher energy is not
//! backtracked away from the contact; `τ` is bisected down to just past the first
//! contact and that step is taken (see [`super::driver`], item 4). Surfaces are
//! in contact where their triangles would meet or, where they merge, their curved
//! sheets ([`surface_contact`]).

use super::acceptance::{self as rules, tangled, Verdict};
use super::mesh_management::MeshManager;
use super::problem::Problem;
use super::report::Rejection;
use super::step::SemiImplicitStep;
use super::system::LinearSystem;
use super::FlowError;
use crate::geometry::{Mesh, PatchSearch, Point};

/// `Γ_n` moved by `τ V⃗`.
pub(super) fn advanced<const D: usize>(mesh: &Mesh<D>, velocity: &[Point<D>], tau: f64) -> Mesh<D> {
    mesh.with_positions(mesh.positions().iter().zip(velocity).map(|(x, v)| x + v * tau).collect())
}

/// The intersection rule's verdict on `trial` and, where `manager` merges and
/// the triangles pass it, a new contact of the curved sheets
/// ([`MeshManager::new_contact`]): retried as an intersection is, with its place.
pub(super) fn surface_contact<const D: usize>(
    mesh: &Mesh<D>,
    trial: &Mesh<D>,
    tau: f64,
    search: &mut PatchSearch,
    manager: Option<&dyn MeshManager<D>>,
) -> (Verdict, Option<[f64; 3]>) {
    let verdict = rules::intersection(mesh, trial, tau, search);
    let curved = (verdict == Verdict::Accept).then(|| manager.and_then(|m| m.new_contact(mesh, trial))).flatten();
    match curved {
        Some(_) => (Verdict::Retry { tau: 0.5 * tau, rejection: Rejection::Intersection }, curved),
        None => (verdict, None),
    }
}

/// Bisections of `τ` that locate a first contact (to `2⁻¹⁰` of the trial step).
const CONTACT_BISECTIONS: usize = 10;

/// The step of `sys` (whose candidate `full`, with its energy, merges curves)
/// shortened to just past the first contact: `τ` is bisected between `0` (the
/// current shape, whose curves do not cross) and `sys.tau`, keeping the upper end a
/// merging candidate; returns that `τ`, its candidate and energy, or `None` if a
/// shortened candidate is tangled or inadmissible (the step is then backtracked as
/// usual).
#[allow(clippy::type_complexity)]
pub(super) fn first_contact<const D: usize>(
    problem: &mut dyn Problem<D>,
    solver: &mut SemiImplicitStep,
    sys: &LinearSystem<'_, D>,
    full: (&Mesh<D>, f64),
) -> Result<Option<(f64, Mesh<D>, f64)>, FlowError> {
    let mut trial = |tau: f64| -> Result<Option<Mesh<D>>, FlowError> {
        let vel = solver.velocity(&LinearSystem { tau, ..*sys })?;
        let candidate = advanced(sys.mesh, &vel.vector, tau);
        Ok(if tangled(sys.mesh, &candidate).is_some() { None } else { Some(candidate) })
    };
    let (mut lo, mut hi) = (0.0, sys.tau);
    let mut best = None;
    for _ in 0..CONTACT_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        match trial(mid)? {
            Some(c) if problem.merges(&c) => {
                hi = mid;
                best = Some(c);
            }
            Some(_) => lo = mid,
            None => return Ok(None),
        }
    }
    // no shorter step merged: the contact lies within the last bisection interval
    let Some(candidate) = best else { return Ok(Some((sys.tau, full.0.clone(), full.1))) };
    let energy = problem.energy(&candidate).map_err(|e| FlowError::Problem(e.0))?;
    Ok(energy.is_finite().then_some((hi, candidate, energy)))
}
