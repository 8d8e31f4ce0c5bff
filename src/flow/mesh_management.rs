//! Mesh management between steps (paper §4.1), behind one trait so that the driver
//! stays dimension-independent: regularization, refinement/coarsening and
//! topological changes. Curves: [`CurveManager`]; surfaces:
//! [`SurfaceManager`](super::SurfaceManager).

use super::report::SurgeryKind;
use super::FlowError;
use crate::geometry::{
    manage_curve, manage_curve_holding, resolve_crossings, CrossingWatch, CurveMesh, CurveRemeshSettings, Hold, Mesh,
    PatchSearch,
};

/// What mesh management did to the mesh after a step.
pub enum Managed<const D: usize> {
    Unchanged,
    /// Same connectivity, moved vertices (tangential regularization).
    Moved(Mesh<D>),
    /// New connectivity (refinement, coarsening, topological change).
    Remeshed(Mesh<D>),
    /// A topological surgery ([`Surgery`]) at the point given: a neck cut, or
    /// components that shrank below the mesh's resolution removed.
    Surgery(Mesh<D>, SurgeryKind, [f64; 3]),
    /// A neck collapsed (3D): the run ends with `pinch_off` on the current mesh.
    PinchOff,
    /// Every component is below the smallest size kept (closed curves with
    /// topological changes: `min_area`): the run ends with `vanished` on the
    /// current mesh.
    Vanished,
}

/// Called by the driver after every accepted step.
pub trait MeshManager<const D: usize>: Send {
    fn manage(&mut self, mesh: &Mesh<D>) -> Result<Managed<D>, FlowError>;
    /// [`MeshManager::manage`] with the flow's intersection search (what the
    /// driver calls): a surface manager checks its result with it, at the cost of
    /// a search where the connectivity is unchanged, and its cut of a new one
    /// serves the trial steps after.
    fn manage_searched(&mut self, mesh: &Mesh<D>, _search: &mut PatchSearch) -> Result<Managed<D>, FlowError> {
        self.manage(mesh)
    }
    /// Components in contact (the flow's intersection rule stopped them a hair
    /// apart) joined into one, if this manager does merges ([`Surgery::merge`]).
    fn merge(&mut self, _mesh: &Mesh<D>) -> Option<Mesh<D>> {
        None
    }
    /// If this manager does merges: where `trial` (which meets itself nowhere)
    /// brings two sheets into contact on the curved surface that its vertex
    /// normals describe, while they were apart on `mesh`'s
    /// ([`crate::geometry::curved_sheet_gap`]). The flat triangles meet only
    /// once the smooth surfaces overlap by up to the faces' depths; the flow
    /// takes this as the contact instead.
    fn new_contact(&self, _mesh: &Mesh<D>, _trial: &Mesh<D>) -> Option<[f64; 3]> {
        None
    }
}

/// Topological surgery of surfaces ([`super::surgery`]): necks cut where the
/// flow would stop with `pinch_off`, and (`merge`) components in contact joined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surgery {
    pub merge: bool,
    /// The flow conserves the enclosed volume: the surgery restores it.
    pub conserve: bool,
}

/// What a pass did: a new connectivity wins over moved vertices.
pub(super) fn outcome<const D: usize>(remeshed: Option<Mesh<D>>, moved: Option<Mesh<D>>) -> Managed<D> {
    match (remeshed, moved) {
        (Some(_), Some(m)) | (Some(m), None) => Managed::Remeshed(m),
        (None, Some(m)) => Managed::Moved(m),
        (None, None) => Managed::Unchanged,
    }
}

/// Switches and resolved parameters of curve mesh management.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveManager {
    pub regularize: bool,
    /// Gauss–Seidel sweeps of the regularization per step.
    pub sweeps: usize,
    pub adapt: bool,
    pub topology_changes: bool,
    pub params: CurveRemeshSettings,
}

impl CurveManager {
    /// Defaults derived from an initial mesh: `h_min`, `h_max` = ¼ and 3× its mean
    /// edge length, `ε` = 1.5× its largest `h_S β_S` (so that a well-resolved initial
    /// curve is not refined at once), minimum area `(h_min)²`.
    pub fn defaults_for(initial: &CurveMesh) -> CurveRemeshSettings {
        let mean = initial.boundary_measure() / initial.num_elements() as f64;
        let mut worst: f64 = 0.0;
        for (l, shift) in initial.lifted_cycles() {
            let n = l.len();
            for k in 0..n {
                let (a, b, c) = (
                    if k == 0 { l[n - 1] - shift } else { l[k - 1] },
                    l[k],
                    if k + 1 == n { l[0] + shift } else { l[k + 1] },
                );
                let (u, v) = (b - a, c - b);
                // turning angle as the chord of the unit tangents, as in the kernels
                let beta = (v / v.norm() - u / u.norm()).norm();
                worst = worst.max(beta * u.norm().max(v.norm()));
            }
        }
        let h_min = 0.25 * mean;
        CurveRemeshSettings {
            epsilon: (1.5 * worst).max(1e-12),
            h_min,
            h_max: 3.0 * mean,
            min_area: h_min * h_min,
            keep_area: false,
            fill_pockets: false,
            keep_apart: false,
        }
    }
}

impl CurveManager {
    /// This manager with a [`CrossingWatch`] kept between steps (what jobs run):
    /// crossing checks are skipped while the last one's certificate holds.
    pub fn watched(self) -> WatchedCurveManager {
        WatchedCurveManager { settings: self, watch: CrossingWatch::default() }
    }
}

/// A [`CurveManager`] with the [`CrossingWatch`] of its flow.
#[derive(Debug, Clone)]
pub struct WatchedCurveManager {
    pub settings: CurveManager,
    pub watch: CrossingWatch,
}

impl MeshManager<2> for CurveManager {
    fn manage(&mut self, mesh: &CurveMesh) -> Result<Managed<2>, FlowError> {
        manage_curves(self, None, mesh)
    }
}

impl MeshManager<2> for WatchedCurveManager {
    fn manage(&mut self, mesh: &CurveMesh) -> Result<Managed<2>, FlowError> {
        manage_curves(&self.settings, Some(&mut self.watch), mesh)
    }
}

/// Adaptivity and regularization in one pass, then topology: it resolves the
/// crossings of the step and any fold the regularization made at a sharp corner,
/// so the result never crosses itself. The watch (if any) serves closed curves.
fn manage_curves(
    s: &CurveManager,
    watch: Option<&mut CrossingWatch>,
    mesh: &CurveMesh,
) -> Result<Managed<2>, FlowError> {
    let fail = |e: crate::geometry::MeshError| FlowError::Management(e.to_string());
    if s.topology_changes && crate::geometry::all_loops_below(mesh, s.params.min_area) {
        return Ok(Managed::Vanished);
    }
    let sweeps = if s.regularize { s.sweeps } else { 0 };
    let (mut remeshed, mut moved) = match manage_curve(mesh, &s.params, s.adapt, sweeps) {
        Err(crate::geometry::MeshError::Empty) => return Ok(Managed::Vanished),
        r => match r.map_err(fail)? {
            (Some(m), true) => (Some(m), None),
            (m, _) => (None, m),
        },
    };
    if s.topology_changes {
        let cur = moved.as_ref().or(remeshed.as_ref()).unwrap_or(mesh);
        let mut hits = match watch {
            Some(w) if cur.period().is_none() => w.crossings_of(cur),
            _ => cur.crossings(),
        };
        if s.params.keep_apart {
            // the loops a pass would make cross another object's only have their
            // tiny segments collapsed, then (if they still cross) are held as
            // they are, and the pass is made again for the others
            let mut hold = vec![Hold::Free; mesh.num_components()];
            loop {
                let cur = moved.as_ref().or(remeshed.as_ref()).unwrap_or(mesh);
                let between = cur.crossings_between_components(&hits);
                if between.is_empty() {
                    break;
                }
                let (label, _) = cur.component_labels();
                let mut crossing: Vec<usize> =
                    between.iter().flat_map(|h| [h.a, h.b]).map(|e| label[cur.elements()[e][0]]).collect();
                crossing.sort_unstable();
                crossing.dedup();
                let mut more = false;
                for c in crossing {
                    let next = match hold[c] {
                        Hold::Free => Hold::Collapse,
                        Hold::Collapse => Hold::CollapseTiny,
                        _ => Hold::Whole,
                    };
                    more |= std::mem::replace(&mut hold[c], next) != Hold::Whole;
                }
                if !more {
                    // the step itself made them cross, not the pass
                    return Ok(Managed::Unchanged);
                }
                (remeshed, moved) = match manage_curve_holding(mesh, &s.params, s.adapt, sweeps, &hold).map_err(fail)? {
                    (Some(m), true) => (Some(m), None),
                    (m, _) => (None, m),
                };
                let cur = moved.as_ref().or(remeshed.as_ref()).unwrap_or(mesh);
                hits = cur.crossings();
            }
        }
        let cur = moved.as_ref().or(remeshed.as_ref()).unwrap_or(mesh);
        match resolve_crossings(cur, &hits, s.params.min_area, s.params.fill_pockets) {
            Err(crate::geometry::MeshError::Empty) => return Ok(Managed::Vanished),
            r => {
                if let Some(m) = r.map_err(fail)? {
                    (remeshed, moved) = (Some(m), None);
                }
            }
        }
        // a component that shrank below min_area vanishes (its shrinking would
        // otherwise hold every step to a fraction of its size)
        let cur = moved.as_ref().or(remeshed.as_ref()).unwrap_or(mesh);
        if let Some(m) = crate::geometry::drop_small_loops(cur, s.params.min_area) {
            (remeshed, moved) = (Some(m), None);
        }
    }
    Ok(outcome(remeshed, moved))
}
