//! Mesh management after an accepted step (paper §4.1), as the driver applies it:
//! the manager's pass, the problem's constraints enforced on its result
//! ([`Problem::constrain`](super::problem::Problem::constrain)), the energy
//! re-evaluated on it, the pattern and the
//! symbolic factorizations rebuilt on a new connectivity.

use super::driver::Flow;
use super::mesh_management::Managed;
use super::report::{StopReason, SurgeryEvent, SurgeryKind, SurgeryRecord};
use super::FlowError;
use crate::fem::Pattern;

impl<const D: usize> Flow<'_, D> {
    /// Apply the mesh manager, if any; a new connectivity rebuilds the pattern and
    /// drops the symbolic factorizations. The energy is re-evaluated on the result.
    /// Returns the stop the management calls for (`pinch_off`, `vanished`), if any.
    pub(super) fn manage_mesh(&mut self) -> Result<Option<StopReason>, FlowError> {
        let Some(manager) = self.manager.as_mut() else { return Ok(None) };
        // what the management changes of a conserving flow's measures (the
        // volume a collapse, a flip or the regularization's tangential moves
        // take off a curved surface) is given back, component by component
        let measures = self.settings.conserves_measure().then(|| self.mesh.component_measures());
        let (mesh, remeshed, cut) = match manager.manage_searched(&self.mesh, &mut self.search)? {
            Managed::Unchanged => return Ok(None),
            Managed::PinchOff => return Ok(Some(StopReason::PinchOff)),
            Managed::Vanished => return Ok(Some(StopReason::Vanished)),
            Managed::Moved(m) => (m, false, None),
            Managed::Remeshed(m) => (m, true, None),
            Managed::Surgery(m, kind, at) => (m, true, Some((kind, at))),
        };
        if mesh.num_vertices() > self.vertex_limit {
            return Err(FlowError::MeshGrowth { vertices: mesh.num_vertices(), limit: self.vertex_limit });
        }
        // the problem's constraints hold for every state the flow holds, as for
        // every step's: a management pass may move or insert vertices past them (a
        // regularized surface bulging out of a segmentation's image box), and a
        // state that broke them would make every trial step from it differ by the
        // constraint's change of energy, however short the step. As after a step,
        // a conserving flow then gets back each component's measure (enforcing a
        // constraint moves vertices, never connects them); a surgery's result has
        // its own measures (the surgery gave the volume back), and so has a pass
        // whose components are not those before it one by one (a curve's
        // topological change that kept their number)
        let measures = measures.map(|before| {
            let after = mesh.component_measures();
            let same = cut.is_none()
                && before.len() == after.len()
                && before.iter().zip(&after).all(|(b, a)| (a - b).abs() <= 0.05 * b.abs());
            if same {
                before
            } else {
                after
            }
        });
        let mesh = match measures {
            Some(measures) => self.problem.constrain(mesh).with_component_measures(&measures),
            None => self.problem.constrain(mesh),
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
        if let Some(e) = super::acceptance::degenerate(&mesh) {
            // management, with the constraints after it, left an element of no
            // measure (a surface's triangle with its three corners moved onto one
            // edge of a segmentation's image box): the next step could not be
            // assembled, so the accepted mesh is kept this time
            tracing::debug!(
                iteration = self.iteration,
                element = e,
                "management left a degenerate element; not applied"
            );
            return Ok(None);
        }
        let intersecting = super::intersections::surface_intersection(&mesh, &mut self.search);
        if let Some((a, b)) =
            intersecting.filter(|_| super::intersections::surface_intersection(&self.mesh, &mut self.search).is_none())
        {
            // the remeshed or regularized surface passes through itself (a vertex
            // moved across a close sheet, by a fold at a sharp ring): the accepted
            // mesh, which does not, is kept this time (one that starts with
            // touching parts, a segmentation's objects split at a neck, may keep them)
            tracing::debug!(iteration = self.iteration, a, b, "management left an intersecting surface; not applied");
            return Ok(None);
        }
        self.mesh = mesh;
        if remeshed {
            self.pattern = Pattern::new(self.mesh.num_vertices(), self.mesh.elements());
            self.solver.reset();
        }
        self.energy = energy;
        if let Some((kind, at)) = cut {
            self.record_surgery(kind, at);
        }
        Ok(None)
    }
}

impl<const D: usize> Flow<'_, D> {
    /// Replace the state by `mesh`, the result of a merge at `at`: a new
    /// connectivity, its energy evaluated, as an iteration of its own that takes no
    /// flow time (so that the history and the checkpoints record it).
    pub(super) fn take_merge(&mut self, mesh: crate::geometry::Mesh<D>, at: [f64; 3]) -> Result<(), FlowError> {
        let energy = self.problem.energy(&mesh).map_err(|e| FlowError::Problem(e.0))?;
        if !energy.is_finite() {
            return Err(FlowError::NonFiniteEnergy { value: energy, iteration: self.iteration });
        }
        self.mesh = mesh;
        self.pattern = Pattern::new(self.mesh.num_vertices(), self.mesh.elements());
        self.solver.reset();
        self.energy = energy;
        self.iteration += 1;
        self.record_surgery(SurgeryKind::Merge, at);
        Ok(())
    }

    /// Record a surgery that made the current state; the convergence test's window
    /// starts again (the energy jumps with the surgery).
    fn record_surgery(&mut self, kind: SurgeryKind, at: [f64; 3]) {
        let event = SurgeryEvent { kind, at, components: self.mesh.num_components() };
        self.surgeries.push(SurgeryRecord { iteration: self.iteration, time: self.time, event });
        self.recent.clear();
    }
}

#[cfg(test)]
mod tests {
    use crate::flow::{Flow, FlowSettings, Managed, MeshManager, Problem, ProblemError, ShapeGradient, SurfaceState};
    use crate::geometry::{circle, Mesh, Point};

    /// Curve shortening above the line `y = 0`, an obstacle (as the film's wetting
    /// layer, or a segmentation's image box).
    struct AboveTheLine;

    impl Problem<2> for AboveTheLine {
        fn name(&self) -> &'static str {
            "above the line"
        }
        fn energy(&mut self, mesh: &Mesh<2>) -> Result<f64, ProblemError> {
            Ok(mesh.boundary_measure())
        }
        fn shape_gradient(&mut self, state: &SurfaceState<'_, 2>) -> Result<ShapeGradient, ProblemError> {
            let n = state.mesh.num_vertices();
            Ok(ShapeGradient { g: vec![1.0; n], f: vec![0.0; n], aux: Vec::new() })
        }
        fn constrain(&self, mut candidate: Mesh<2>) -> Mesh<2> {
            let x = candidate.positions().iter().map(|p| Point::<2>::new(p[0], p[1].max(0.0))).collect();
            candidate.set_positions(x);
            candidate
        }
    }

    /// Curve shortening above the line of a circle of 64 vertices, radius 0.25,
    /// centred at `(0, y)`, with the mesh manager `manager`.
    fn above_the_line<'p>(
        problem: &'p mut AboveTheLine,
        y: f64,
        settings: FlowSettings,
        manager: Box<dyn MeshManager<2>>,
    ) -> Flow<'p, 2> {
        let mesh = circle([0.0, y], 0.25, 64).unwrap();
        Flow::new(problem, mesh, settings).unwrap().with_mesh_manager(manager)
    }

    /// A management pass that moves every vertex down by 0.1, past the obstacle
    /// near the curve's bottom.
    struct Sinking;

    impl MeshManager<2> for Sinking {
        fn manage(&mut self, mesh: &Mesh<2>) -> Result<Managed<2>, crate::flow::FlowError> {
            let x = mesh.positions().iter().map(|p| Point::<2>::new(p[0], p[1] - 0.1)).collect();
            Ok(Managed::Moved(mesh.with_positions(x)))
        }
    }

    /// The state after a management pass keeps the problem's constraints, and its
    /// recorded energy is the energy of that state: otherwise every trial step
    /// from it would differ from it by the constraint's change of energy, however
    /// short the step.
    #[test]
    fn a_managed_state_keeps_the_constraints() {
        let mut problem = AboveTheLine;
        let settings = FlowSettings { tau: 1e-4, ..FlowSettings::default() };
        let mut flow = above_the_line(&mut problem, 0.3, settings, Box::new(Sinking));
        for _ in 0..3 {
            assert!(flow.step().unwrap().accepted);
            assert!(flow.mesh().positions().iter().all(|p| p[1] >= 0.0));
            assert_eq!(flow.energy(), flow.mesh().boundary_measure());
        }
        assert!(flow.mesh().positions().iter().filter(|p| p[1] == 0.0).count() > 4);
    }

    /// A management pass that moves vertex 1 onto vertex 0: a segment of no length.
    struct Collapsing;

    impl MeshManager<2> for Collapsing {
        fn manage(&mut self, mesh: &Mesh<2>) -> Result<Managed<2>, crate::flow::FlowError> {
            let mut x = mesh.positions().to_vec();
            x[1] = x[0];
            Ok(Managed::Moved(mesh.with_positions(x)))
        }
    }

    /// A management pass that leaves an element of no measure is not applied: the
    /// accepted step's mesh is kept, and the flow goes on from it (the next step
    /// could not be assembled on the degenerate one).
    #[test]
    fn a_management_pass_leaving_a_degenerate_element_is_not_applied() {
        let mut problem = AboveTheLine;
        let settings = FlowSettings { tau: 1e-4, ..FlowSettings::default() };
        let mut flow = above_the_line(&mut problem, 0.5, settings, Box::new(Collapsing));
        for _ in 0..3 {
            assert!(flow.step().unwrap().accepted);
            let x = flow.mesh().positions();
            assert!((x[1] - x[0]).norm() > 0.01);
            assert_eq!(flow.energy(), flow.mesh().boundary_measure());
        }
    }

    /// A management pass that splits every segment in two.
    struct Doubling;

    impl MeshManager<2> for Doubling {
        fn manage(&mut self, mesh: &Mesh<2>) -> Result<Managed<2>, crate::flow::FlowError> {
            let mut x = mesh.positions().to_vec();
            let mut elements = Vec::with_capacity(2 * mesh.num_elements());
            for &[a, b] in mesh.elements() {
                x.push((x[a] + x[b]) * 0.5);
                let m = x.len() - 1;
                elements.extend([[a, m], [m, b]]);
            }
            Ok(Managed::Remeshed(Mesh::from_trusted_parts(x, elements)))
        }
    }

    /// Mesh management that refines without bound ends the run with a message
    /// once the mesh would pass its allowance (a circle of 64 vertices may grow to
    /// 100,000), on the last state it held.
    #[test]
    fn a_mesh_that_grows_without_bound_ends_the_run() {
        let mut problem = AboveTheLine;
        let settings = FlowSettings { tau: 1e-6, ..FlowSettings::default() };
        let mut flow = above_the_line(&mut problem, 0.5, settings, Box::new(Doubling));
        let mut steps = 0;
        let error = loop {
            match flow.step() {
                Ok(report) => {
                    assert!(report.accepted && report.stop.is_none());
                    steps += 1;
                }
                Err(e) => break e,
            }
        };
        // 64 · 2^11 = 131,072 > 100,000
        assert_eq!(steps, 10);
        assert_eq!(error, crate::flow::FlowError::MeshGrowth { vertices: 131_072, limit: 100_000 });
        assert_eq!(flow.mesh().num_vertices(), 65_536);
        assert!(error.to_string().contains("flow.backtracking"));
    }

    /// A management pass that fails on its first call (a fold it cannot resolve).
    struct FailingOnce(bool);

    impl MeshManager<2> for FailingOnce {
        fn manage(&mut self, _mesh: &Mesh<2>) -> Result<Managed<2>, crate::flow::FlowError> {
            if std::mem::replace(&mut self.0, true) {
                return Ok(Managed::Unchanged);
            }
            Err(crate::flow::FlowError::Management("segments 1 and 3 intersect".into()))
        }
    }

    /// A step whose shape the management cannot repair is taken back, and the
    /// next call tries half of it; with `tau_min` above that half the run stops
    /// `tau_min`, saying why.
    #[test]
    fn a_step_the_management_cannot_repair_is_taken_back() {
        let mut problem = AboveTheLine;
        let settings = FlowSettings { tau: 1e-3, ..FlowSettings::default() };
        let mut flow = above_the_line(&mut problem, 0.5, settings, Box::new(FailingOnce(false)));
        let mesh = flow.mesh().clone();
        let first = flow.step().unwrap();
        assert!(!first.accepted && first.stop.is_none());
        assert_eq!(first.rejected, Some(crate::flow::Rejection::Management));
        assert_eq!((flow.iteration, flow.time), (0, 0.0));
        assert_eq!(flow.mesh(), &mesh);
        let second = flow.step().unwrap();
        assert!(second.accepted);
        assert_eq!((flow.iteration, flow.tau), (1, 5e-4));
        let mut problem = AboveTheLine;
        let settings = FlowSettings { tau: 1e-3, tau_min: 6e-4, ..FlowSettings::default() };
        let mut flow = above_the_line(&mut problem, 0.5, settings, Box::new(FailingOnce(false)));
        let stop = flow.run(&std::sync::atomic::AtomicBool::new(false), |_| {}).unwrap();
        assert_eq!(stop, crate::flow::StopReason::TauMin);
        assert_eq!(flow.stop_cause(), Some(crate::flow::Rejection::Management));
    }
}
