//! Mesh management of surfaces (paper §4.1): adaptation, regularization, the
//! pinch-off test, and with [`Surgery`] the topological surgeries (a neck cut, a
//! merge, components that vanish).

use super::mesh_management::{outcome, Managed, MeshManager, Surgery};
use super::report::SurgeryKind;
use super::FlowError;
use crate::geometry::{
    adapt_surface, adapt_surface_except, closest_facing_vertices, curved_sheet_gap, cut_neck, edge_statistics,
    freeze_around, regularize_surface, revert_new_intersections, surface_union, zip_sheets, PatchSearch, Point,
    SurfaceMesh, SurfaceRemeshSettings,
};

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

/// The mean of a surface's vertices.
fn centroid(m: &SurfaceMesh) -> [f64; 3] {
    let n = m.num_vertices().max(1) as f64;
    std::array::from_fn(|k| m.positions().iter().map(|p| p[k]).sum::<f64>() / n)
}

fn edge_stats(m: &SurfaceMesh) -> (f64, (f64, f64)) {
    let (mean, hb, bh) = edge_statistics(m);
    (mean, (hb, bh))
}

/// Adaptations made again with more vertices frozen where the last one carried
/// a triangle through a close sheet ([`SurfaceManager::apart`]): within 1, 2 and
/// 4 edges of the triangles that meet.
pub const APART_ROUNDS: usize = 3;

/// Smallest angle the surface management keeps while a neck collapses: below it,
/// once the neck is thinner than `4 h_min`, the neck counts as pinched.
pub const PINCH_MIN_ANGLE_DEG: f64 = 10.0;

impl MeshManager<3> for SurfaceManager {
    /// Pinch-off is declared when a neck is thinner than `h_min / 2` (curvature above
    /// `pinch_curvature`), or thinner than `4 h_min` while the managed mesh can no
    /// longer keep its angles above `PINCH_MIN_ANGLE_DEG` (elements of at least
    /// `h_min` around a ring that small).
    fn manage(&mut self, mesh: &SurfaceMesh) -> Result<Managed<3>, FlowError> {
        self.manage_searched(mesh, &mut PatchSearch::default())
    }

    /// [`MeshManager::manage`], its result checked for intersections by `search`.
    fn manage_searched(&mut self, mesh: &SurfaceMesh, search: &mut PatchSearch) -> Result<Managed<3>, FlowError> {
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
        let (remeshed, moved) = self.apart(mesh, remeshed, moved, search);
        // the adaptation parted a neck itself (a collapse, or a cluster of tiny
        // triangles replaced across it): with surgery a pinch like the designed
        // one, recorded; with the pinch test alone the paper's stop
        let parts = mesh.component_labels().1;
        if let Some(r) = remeshed.as_ref().filter(|r| r.component_labels().1 > parts) {
            match (self.surgery, self.pinch_curvature) {
                (Some(_), _) => {
                    let components = r.component_labels().1;
                    let parted = self.conserved(moved.unwrap_or_else(|| r.clone()), mesh);
                    let at = super::surgery::sharpest_edge(mesh).map_or_else(|| centroid(mesh), |p| [p[0], p[1], p[2]]);
                    tracing::info!(?at, components, "neck parted by the remeshing (pinch-off surgery)");
                    return Ok(Managed::Surgery(parted, SurgeryKind::Pinch, at));
                }
                (None, Some(_)) => return Ok(Managed::PinchOff),
                (None, None) => {}
            }
        }
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

    /// Two sheets in contact become one, if the surgery merges: zipped on the
    /// mesh where two vertices closer than the initial mean edge face each other
    /// ([`SurfaceManager::zipped`]), else rebuilt by a merge on a grid of that
    /// edge, bridged over twice it.
    fn merge(&mut self, mesh: &SurfaceMesh) -> Option<SurfaceMesh> {
        self.surgery.filter(|s| s.merge)?;
        let spacing = self.surgery_spacing();
        let merged = match self.zipped(mesh, spacing) {
            Some(m) => m,
            None => self.operate(mesh, super::surgery::Operation::Merge { blend: 2.0 * spacing })?,
        };
        // a new surface: a ring that a cut did not part before is gone
        self.declined = None;
        tracing::info!(components = merged.component_labels().1, vertices = merged.num_vertices(), "surfaces merged");
        Some(merged)
    }

    fn new_contact(&self, mesh: &SurfaceMesh, trial: &SurfaceMesh) -> Option<[f64; 3]> {
        self.surgery.filter(|s| s.merge)?;
        let (gap, at) = curved_sheet_gap(trial.positions(), trial.elements()).filter(|&(g, _)| g < 0.0)?;
        let before = curved_sheet_gap(mesh.positions(), mesh.elements());
        before.is_none_or(|(g, _)| g >= 0.0).then(|| {
            tracing::debug!(gap, ?at, "curved sheets in contact");
            at
        })
    }
}

impl SurfaceManager {
    /// The adaptation `remeshed` and the regularization `moved` of `mesh` (which
    /// meets itself nowhere), or what of them passes through no sheet: where the
    /// management carried a vertex through a close sheet (touching objects of a
    /// segmentation, the parts of a neck split), the adaptation is made again
    /// with the vertices around the triangles that meet left as they are
    /// ([`adapt_surface_except`], up to [`APART_ROUNDS`] times, each freezing
    /// twice as far around what still meets; else not taken),
    /// and the regularization's moves of the triangles that meet are undone
    /// ([`revert_new_intersections`]). Checked only where the result meets itself.
    fn apart(
        &self,
        mesh: &SurfaceMesh,
        remeshed: Option<SurfaceMesh>,
        moved: Option<SurfaceMesh>,
        search: &mut PatchSearch,
    ) -> (Option<SurfaceMesh>, Option<SurfaceMesh>) {
        let mut meets = |m: &SurfaceMesh| !search.intersections(m.positions(), m.elements(), 1).is_empty();
        let result = moved.as_ref().or(remeshed.as_ref());
        if result.is_none_or(|m| !meets(m)) || meets(mesh) {
            return (remeshed, moved);
        }
        // the adaptation kept away from where it meets
        let (mut remeshed, mut again) = (remeshed, false);
        let mut frozen = vec![false; mesh.num_vertices()];
        for round in 0..=APART_ROUNDS {
            let Some(r) = remeshed.take() else { break };
            let pairs = search.intersections(r.positions(), r.elements(), usize::MAX);
            if pairs.is_empty() {
                remeshed = Some(r);
                break;
            }
            if round < APART_ROUNDS {
                freeze_around(mesh, &r, &pairs, f64::from(1u32 << round), &mut frozen);
                remeshed = adapt_surface_except(mesh, &self.params, &frozen);
                again = true;
            }
        }
        // the regularization of what is kept, undone where it meets
        let base = remeshed.as_ref().unwrap_or(mesh);
        let moved = moved.map(|m| if again { regularize_surface(base, self.sweeps) } else { m }).and_then(|m| {
            revert_new_intersections(base.positions(), m.positions(), base.elements(), 8, search)
                .map(|x| base.with_positions(x))
        });
        tracing::debug!(adapted = remeshed.is_some(), "management kept apart from a close sheet");
        (remeshed, moved)
    }

    /// `mesh` with the closest two facing vertices within `reach` zipped
    /// ([`zip_sheets`]), tidied by the management (two rounds, else as zipped),
    /// and for a conserving flow given back its volume; `None` where no two face
    /// each other, the zipper declines, or the zipped surface meets itself.
    fn zipped(&self, mesh: &SurfaceMesh, reach: f64) -> Option<SurfaceMesh> {
        let (a, b) = closest_facing_vertices(mesh, reach)?;
        let zipped = zip_sheets(mesh, a, b, reach)?;
        let mut search = PatchSearch::default();
        let mut sound = |m: &SurfaceMesh| search.intersections(m.positions(), m.elements(), 1).is_empty();
        if !sound(&zipped) {
            tracing::debug!("a zipped surface meets itself");
            return None;
        }
        let tidied = self.tidy(zipped.clone(), 2);
        let kept = if sound(&tidied) { tidied } else { zipped };
        tracing::debug!(at = ?(mesh.positions()[a] + mesh.positions()[b]) * 0.5, "sheets zipped");
        Some(self.conserved(kept, mesh))
    }

    /// The grid of a surgery: the mean edge the management's sizes aim at (4
    /// `h_min`: the initial mean edge by default).
    fn surgery_spacing(&self) -> f64 {
        (4.0 * self.params.h_min).min(self.params.h_max)
    }

    /// `mesh` rebuilt by `op` and tidied ([`SurfaceManager::rebuilt`]) and, for a
    /// conserving flow, given back its volume; `None` if the rebuild fails.
    fn operate(&self, mesh: &SurfaceMesh, op: super::surgery::Operation) -> Option<SurfaceMesh> {
        Some(self.conserved(self.rebuilt(mesh, op)?, mesh))
    }

    /// `mesh` rebuilt by the level-set operation `op`, tidied (four rounds of the
    /// management's adaptation and regularization: the slivers of marching
    /// tetrahedra made sound); `None` if the rebuild fails.
    fn rebuilt(&self, mesh: &SurfaceMesh, op: super::surgery::Operation) -> Option<SurfaceMesh> {
        match super::surgery::rebuild(mesh, self.surgery_spacing(), op) {
            Ok(m) => Some(self.tidy(m?, 4)),
            Err(e) => {
                tracing::warn!("the surface a surgery rebuilt is invalid: {e}");
                None
            }
        }
    }

    /// The level-set cut `op` at `at` ([`SurfaceManager::operate`]) made on the
    /// object there alone (the component of the vertex nearest to `at`, with its
    /// cavities): the other objects keep their triangles, and their signed
    /// distances are not sampled.
    fn cut_object(&self, mesh: &SurfaceMesh, at: Point<3>, op: super::surgery::Operation) -> Option<SurfaceMesh> {
        let objects = mesh.objects();
        let near = (mesh.positions().iter().enumerate())
            .min_by(|a, b| (a.1 - at).norm_squared().total_cmp(&(b.1 - at).norm_squared()))?
            .0;
        let root = objects.owner[objects.vertex_component[near]];
        let mine: Vec<bool> = objects.owner.iter().map(|&o| o == root).collect();
        let Some(others) = mesh.with_components(&mine.iter().map(|m| !m).collect::<Vec<_>>()) else {
            return self.operate(mesh, op);
        };
        let object = mesh.with_components(&mine)?;
        let cut = self.rebuilt(&object, op)?;
        let joined = surface_union(&[others, cut]).ok()?;
        Some(self.conserved(joined, mesh))
    }

    /// `rounds` of the management's adaptation and regularization (a traced
    /// surface's slivers made sound).
    pub fn tidy(&self, mut m: SurfaceMesh, rounds: usize) -> SurfaceMesh {
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
        match self.cut_object(mesh, at, op) {
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
