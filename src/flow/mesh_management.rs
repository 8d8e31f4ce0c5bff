//! Mesh management between steps (paper §4.1), behind one trait so that the driver
//! stays dimension-independent: regularization, refinement/coarsening and
//! topological changes. Curves: [`CurveManager`].

use super::report::SurgeryKind;
use super::FlowError;
use crate::geometry::{
    adapt_surface, cut_neck, edge_statistics, manage_curve, manage_curve_holding, regularize_surface,
    resolve_crossings, CrossingWatch, CurveMesh, CurveRemeshSettings, Hold, Mesh, SurfaceMesh, SurfaceRemeshSettings,
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
    /// Components in contact (the flow's intersection rule stopped them a hair
    /// apart) joined into one, if this manager does merges ([`Surgery::merge`]).
    fn merge(&mut self, _mesh: &Mesh<D>) -> Option<Mesh<D>> {
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
fn outcome<const D: usize>(remeshed: Option<Mesh<D>>, moved: Option<Mesh<D>>) -> Managed<D> {
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

/// Switches and resolved parameters of surface mesh management.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceManager {
    pub regularize: bool,
    pub sweeps: usize,
    pub adapt: bool,
    pub params: SurfaceRemeshSettings,
    /// Pinch-off is declared when some edge has `β/h` (angle between the normals of
    /// its two triangles over its length: a principal curvature) above this, i.e. a
    /// neck radius below its inverse, which the mesh (`h ≥ h_min`) cannot resolve.
    pub pinch_curvature: Option<f64>,
    /// With surgery, a pinch-off cuts the neck and the flow goes on.
    pub surgery: Option<Surgery>,
    /// Run state (`None` at the start): the sharpest ring's `β/h` at which a cut
    /// last did not part the surface (a crease, not a neck); no cut is tried
    /// again until a ring is twice as sharp.
    pub declined: Option<f64>,
}

impl SurfaceManager {
    /// Defaults derived from an initial surface: `h_min`, `h_max` = ¼ and 3× its mean
    /// edge, `ε` = 1.5× its largest edge `h β`, 120° angle limit, pinch-off at a
    /// curvature of `2/h_min` (neck radius `h_min/2`).
    pub fn defaults_for(initial: &SurfaceMesh) -> (SurfaceRemeshSettings, f64) {
        let (mean, worst) = edge_stats(initial);
        let h_min = 0.25 * mean;
        (
            SurfaceRemeshSettings {
                epsilon: (1.5 * worst.0).max(1e-12),
                h_min,
                h_max: 3.0 * mean,
                max_angle_deg: 120.0,
            },
            2.0 / h_min,
        )
    }
}

fn edge_stats(m: &SurfaceMesh) -> (f64, (f64, f64)) {
    let (mean, hb, bh) = edge_statistics(m);
    (mean, (hb, bh))
}

/// Smallest angle the surface management keeps while a neck collapses: below it,
/// once the neck is thinner than `4 h_min`, the neck counts as pinched.
pub const PINCH_MIN_ANGLE_DEG: f64 = 10.0;

impl MeshManager<3> for SurfaceManager {
    /// Pinch-off is declared when a neck is thinner than `h_min / 2` (curvature above
    /// `pinch_curvature`), or thinner than `4 h_min` while the managed mesh can no
    /// longer keep its angles above `PINCH_MIN_ANGLE_DEG` (elements of at least
    /// `h_min` around a ring that small).
    fn manage(&mut self, mesh: &SurfaceMesh) -> Result<Managed<3>, FlowError> {
        if let Some(done) = self.surgery.and_then(|_| self.shrunk_away(mesh)) {
            return Ok(done);
        }
        let curvature = self.pinch_curvature.map(|k| (k, edge_stats(mesh).1 .1));
        if let Some((_, c)) = curvature.filter(|&(k, c)| c > k) {
            match self.pinch(mesh, c) {
                Managed::Unchanged => {}
                done => return Ok(done),
            }
        }
        let remeshed = if self.adapt { adapt_surface(mesh, &self.params) } else { None };
        let moved = if self.regularize {
            Some(regularize_surface(remeshed.as_ref().unwrap_or(mesh), self.sweeps))
        } else {
            None
        };
        if let Some((_, c)) = curvature.filter(|&(k, c)| c > 0.125 * k) {
            let result = moved.as_ref().or(remeshed.as_ref()).unwrap_or(mesh);
            if result.quality().min_angle_deg < PINCH_MIN_ANGLE_DEG {
                match self.pinch(mesh, c) {
                    Managed::Unchanged => {}
                    done => return Ok(done),
                }
            }
        }
        Ok(outcome(remeshed, moved))
    }

    /// Two sheets in contact become one (a merge on a grid of the initial mean
    /// edge, bridged over twice that), if the surgery merges.
    fn merge(&mut self, mesh: &SurfaceMesh) -> Option<SurfaceMesh> {
        self.surgery.filter(|s| s.merge)?;
        let spacing = self.surgery_spacing();
        let merged = self.operate(mesh, super::surgery::Operation::Merge { blend: 2.0 * spacing })?;
        // a new surface: a ring that a cut did not part before is gone
        self.declined = None;
        tracing::info!(components = merged.component_labels().1, vertices = merged.num_vertices(), "surfaces merged");
        Some(merged)
    }
}

impl SurfaceManager {
    /// The grid of a surgery: the mean edge the management's sizes aim at (4
    /// `h_min`: the initial mean edge by default).
    fn surgery_spacing(&self) -> f64 {
        (4.0 * self.params.h_min).min(self.params.h_max)
    }

    /// `mesh` rebuilt by `op`, tidied (four rounds of the management's adaptation
    /// and regularization: the slivers of marching tetrahedra made sound) and,
    /// for a conserving flow, given back its volume; `None` if the rebuild fails.
    fn operate(&self, mesh: &SurfaceMesh, op: super::surgery::Operation) -> Option<SurfaceMesh> {
        let mut m = match super::surgery::rebuild(mesh, self.surgery_spacing(), op) {
            Ok(m) => m?,
            Err(e) => {
                tracing::warn!("the surface a surgery rebuilt is invalid: {e}");
                return None;
            }
        };
        m = self.tidy(m, 4);
        Some(self.conserved(m, mesh))
    }

    /// `rounds` of the management's adaptation and regularization.
    fn tidy(&self, mut m: SurfaceMesh, rounds: usize) -> SurfaceMesh {
        for _ in 0..rounds {
            if let Some(a) = adapt_surface(&m, &self.params) {
                m = a;
            }
            m = regularize_surface(&m, self.sweeps.max(3));
        }
        m
    }

    /// `m`, a surgery's result on `before`, with the volume of `before` if the
    /// flow conserves it.
    fn conserved(&self, m: SurfaceMesh, before: &SurfaceMesh) -> SurfaceMesh {
        match self.surgery.is_some_and(|s| s.conserve) {
            true => super::surgery::with_volume(m, before.enclosed_measure()),
            false => m,
        }
    }

    /// With surgery, the components whose volume is that of a ball of radius below
    /// `h_min` (which the mesh no longer resolves: a shrinking sphere's curvature
    /// reaches the pinch test's at radius `h_min / 2`) removed; `Vanished` if none
    /// is left, `None` if none is that small.
    fn shrunk_away(&self, mesh: &SurfaceMesh) -> Option<Managed<3>> {
        let smallest = 4.0 / 3.0 * std::f64::consts::PI * self.params.h_min.powi(3);
        let keep: Vec<bool> = mesh.component_measures().iter().map(|&v| v.abs() >= smallest).collect();
        let gone = keep.iter().position(|k| !k)?;
        let (labels, _) = mesh.component_labels();
        let x = mesh.positions();
        let members: Vec<usize> = (0..x.len()).filter(|&v| labels[v] == gone).collect();
        let at = std::array::from_fn(|k| members.iter().map(|&v| x[v][k]).sum::<f64>() / members.len() as f64);
        tracing::info!(?at, left = keep.iter().filter(|k| **k).count(), "a surface shrank away");
        Some(match mesh.with_components(&keep) {
            Some(m) => Managed::Surgery(m, SurgeryKind::Vanish, at),
            None => Managed::Vanished,
        })
    }

    /// A neck too thin for the mesh, with surgery: cut at its sharpest edge on the
    /// mesh ([`cut_neck`]), or where that does not part it by the level set (lowered
    /// by two grid spacings within three of it); without surgery the run's
    /// `pinch_off` stop.
    fn pinch(&mut self, mesh: &SurfaceMesh, sharpness: f64) -> Managed<3> {
        let (Some(_), Some(at)) = (self.surgery, super::surgery::sharpest_edge(mesh)) else {
            return Managed::PinchOff;
        };
        if self.declined.is_some_and(|d| sharpness < 2.0 * d) {
            return Managed::Unchanged;
        }
        let parts = mesh.component_labels().1;
        // on the mesh itself: the triangles within three neck radii (the inverse
        // of the ring's curvature) of the ring removed and both holes capped; the
        // rest of the surface keeps its triangles
        let radius = (3.0 / sharpness).max(2.0 * self.params.h_min);
        if let Some(cut) = cut_neck(mesh, at, radius).filter(|c| c.component_labels().1 > parts) {
            let cut = self.conserved(self.tidy(cut, 2), mesh);
            if cut.component_labels().1 > parts {
                self.declined = None;
                let (at, components) = ([at[0], at[1], at[2]], cut.component_labels().1);
                tracing::info!(?at, components, vertices = cut.num_vertices(), "neck cut (pinch-off surgery)");
                return Managed::Surgery(cut, SurgeryKind::Pinch, at);
            }
        }
        // else by the level set: a neck the ball does not part (a wide one)
        let spacing = self.surgery_spacing();
        let op = super::surgery::Operation::Cut { at, radius: 3.0 * spacing, depth: 2.0 * spacing };
        match self.operate(mesh, op) {
            // a cut that parts the surface: the neck was one
            Some(cut) if cut.component_labels().1 > parts => {
                self.declined = None;
                let (at, components) = ([at[0], at[1], at[2]], cut.component_labels().1);
                tracing::info!(?at, components, vertices = cut.num_vertices(), "neck cut (pinch-off surgery)");
                Managed::Surgery(cut, SurgeryKind::Pinch, at)
            }
            // no neck there (a crease, such as a fresh merge's bridge, which the
            // flow opens): the management goes on as usual
            Some(_) => {
                self.declined = Some(sharpness);
                tracing::debug!(at = ?[at[0], at[1], at[2]], "a sharp ring that a cut does not part: no pinch");
                Managed::Unchanged
            }
            None => Managed::PinchOff,
        }
    }
}
