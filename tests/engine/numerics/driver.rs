//! The driver's rules on functionals with a known answer: backtracking, resumption,
//! stop reasons and re-discretization after failed backtracking.

use super::*;

/// A functional with a minimizer: `J = (|Ω| − A₀)² + ε|Γ|`, `G = εκ + 2(|Ω| − A₀)`.
/// Its area term is explicit in the semi-implicit step, so a large τ overshoots A₀.
struct AreaTarget {
    target: f64,
    eps: f64,
}

impl<const D: usize> Problem<D> for AreaTarget {
    fn name(&self) -> &'static str {
        "area_target"
    }
    fn energy(&mut self, mesh: &Mesh<D>) -> Result<f64, ProblemError> {
        Ok((mesh.enclosed_measure() - self.target).powi(2) + self.eps * mesh.boundary_measure())
    }
    fn shape_gradient(&mut self, s: &SurfaceState<'_, D>) -> Result<ShapeGradient, ProblemError> {
        let n = s.mesh.num_vertices();
        let f = 2.0 * (s.mesh.enclosed_measure() - self.target);
        Ok(ShapeGradient { g: vec![self.eps; n], f: vec![f; n], aux: Vec::new() })
    }
}

#[test]
fn backtracking_keeps_a_too_large_step_monotone() {
    let mut problem = AreaTarget { target: 2.0 * std::f64::consts::PI, eps: 0.1 };
    let target = problem.target;
    let mut run = |backtracking: bool, iterations: usize| {
        let settings = FlowSettings {
            tau: 1.0,
            max_iterations: iterations,
            tolerance: 0.0,
            backtracking,
            ..FlowSettings::default()
        };
        let mut flow = Flow::new(&mut problem, circle([0.0, 0.0], 1.0, 128).unwrap(), settings).unwrap();
        let mut energies = vec![flow.energy()];
        let mut backtracks = 0;
        loop {
            let r = flow.step().unwrap();
            backtracks += r.backtracks;
            if r.accepted {
                energies.push(flow.energy());
            }
            if r.stop.is_some() {
                break;
            }
        }
        (energies, backtracks, flow.mesh().enclosed_measure())
    };
    let (energies, backtracks, area) = run(true, 30);
    eprintln!("backtracks {backtracks}, energies {:?}, final area {area}", &energies[..5]);
    assert!(backtracks > 0, "the test must exercise backtracking");
    assert!(energies.windows(2).all(|w| w[1] <= w[0]), "energy history not monotone: {energies:?}");
    assert!((area - target).abs() < 0.05 * target, "converges near the target area: {area}");
    // the same τ without backtracking raises the energy
    let (energies, _, _) = run(false, 3);
    assert!(energies.windows(2).any(|w| w[1] > w[0]), "without backtracking τ = 1 overshoots: {energies:?}");
}

#[test]
fn resuming_from_a_checkpoint_reproduces_the_uninterrupted_run() {
    let mut problem = CurvatureFlow { gamma: 1.0, lambda: 0.5 };
    let settings = FlowSettings { tau: 2e-3, max_iterations: 60, tolerance: 0.0, ..FlowSettings::default() };
    let start = || ellipse([0.1, 0.2], [1.0, 0.7], 0.3, 96).unwrap();
    let history = |flow: &mut Flow<'_, 2>, out: &mut Vec<(usize, f64, f64, f64)>| {
        flow.run(&AtomicBool::new(false), |f| {
            let p = f.progress();
            out.push((p.iteration, p.time, p.tau, p.energy));
        })
        .unwrap()
    };
    let mut full = Vec::new();
    let mut flow = Flow::new(&mut problem, start(), settings.clone()).unwrap();
    assert_eq!(history(&mut flow, &mut full), StopReason::MaxIterations);
    let final_full = flow.mesh().clone();

    let mut first = Vec::new();
    drop(flow);
    let mut flow = Flow::new(&mut problem, start(), FlowSettings { max_iterations: 25, ..settings.clone() }).unwrap();
    history(&mut flow, &mut first);
    // through JSON, as stored
    let json = serde_json::to_string(&flow.checkpoint()).unwrap();
    let cp: shapeflow::flow::Checkpoint = serde_json::from_str(&json).unwrap();
    let mut second = Vec::new();
    drop(flow);
    let mut resumed = Flow::resume(&mut problem, &cp, settings).unwrap();
    history(&mut resumed, &mut second);
    first.extend_from_slice(&second[1..]); // the resumed run reports its start again
    assert_eq!(first, full, "histories differ");
    assert_eq!(resumed.mesh(), &final_full, "final meshes differ");
}

#[test]
fn stop_reasons_converged_cancelled_and_tau_min() {
    let mut problem = AreaTarget { target: 2.0 * std::f64::consts::PI, eps: 0.1 };
    let start = || circle([0.0, 0.0], 1.0, 64).unwrap();
    // converged: relative energy change below the tolerance
    let s = FlowSettings { tau: 0.05, tolerance: 1e-9, max_iterations: 5000, ..FlowSettings::default() };
    let mut flow = Flow::new(&mut problem, start(), s).unwrap();
    assert_eq!(flow.run(&AtomicBool::new(false), |_| {}).unwrap(), StopReason::Converged);
    assert!(flow.iteration() < 5000);
    // cancelled: the flag is checked before every step
    let cancel = AtomicBool::new(false);
    let s = FlowSettings { tau: 1e-3, tolerance: 0.0, max_iterations: 100, ..FlowSettings::default() };
    drop(flow);
    let mut flow = Flow::new(&mut problem, start(), s).unwrap();
    let stop = flow
        .run(&cancel, |f| {
            if f.iteration() == 5 {
                cancel.store(true, std::sync::atomic::Ordering::Relaxed);
            }
        })
        .unwrap();
    assert_eq!((stop, flow.iteration()), (StopReason::Cancelled, 5));
    // tau_min: every admissible τ overshoots
    let s = FlowSettings { tau: 1.0, tau_min: 0.5, tolerance: 0.0, ..FlowSettings::default() };
    drop(flow);
    let mut flow = Flow::new(&mut problem, start(), s).unwrap();
    assert_eq!(flow.run(&AtomicBool::new(false), |_| {}).unwrap(), StopReason::TauMin);
    assert_eq!(flow.iteration(), 0);
    let cause = flow.stop_cause();
    assert_eq!(cause, Some(Rejection::StepControl), "{cause:?}");
    // max_iterations
    let s = FlowSettings { tau: 1e-3, tolerance: 0.0, max_iterations: 7, ..FlowSettings::default() };
    drop(flow);
    let mut flow = Flow::new(&mut problem, start(), s).unwrap();
    assert_eq!(flow.run(&AtomicBool::new(false), |_| {}).unwrap(), StopReason::MaxIterations);
    assert_eq!(flow.iteration(), 7);
}

/// Curve shortening whose discretization of the current shape is "stale": the
/// energy of the start was evaluated too low by `bias` (as a followed bulk mesh can
/// be, in shape design), so every trial step looks like an increase until the
/// problem re-evaluates the current shape afresh.
struct StaleStart {
    bias: f64,
    fresh: bool,
    evaluations: std::sync::Mutex<usize>,
}

impl Problem<2> for StaleStart {
    fn name(&self) -> &'static str {
        "stale_start"
    }
    fn energy(&mut self, mesh: &Mesh<2>) -> Result<f64, ProblemError> {
        let mut n = self.evaluations.lock().unwrap();
        *n += 1;
        Ok(mesh.boundary_measure() - if *n == 1 { self.bias } else { 0.0 })
    }
    fn shape_gradient(&mut self, state: &SurfaceState<'_, 2>) -> Result<ShapeGradient, ProblemError> {
        let n = state.mesh.num_vertices();
        Ok(ShapeGradient { g: vec![1.0; n], f: vec![0.0; n], aux: Vec::new() })
    }
    fn rediscretize(&mut self, mesh: &Mesh<2>) -> Result<Option<f64>, ProblemError> {
        Ok(self.fresh.then(|| mesh.boundary_measure()))
    }
}

/// Driver item 5: when backtracking fails, the current state is re-evaluated on a
/// fresh discretization and the step is tried again; without that the run stops
/// with `tau_min` although the flow has not converged.
#[test]
fn failed_backtracking_rediscretizes_the_current_state_once() {
    let settings =
        FlowSettings { tau: 1e-2, tau_min: 1e-6, tolerance: 0.0, max_iterations: 5, ..FlowSettings::default() };
    let start = || circle([0.0, 0.0], 1.0, 64).unwrap();
    // a bias far above what a step gains: stale, the first step cannot be taken
    let mut stale = StaleStart { bias: 0.1, fresh: false, evaluations: Default::default() };
    let mut flow = Flow::new(&mut stale, start(), settings.clone()).unwrap();
    let r = flow.step().unwrap();
    assert_eq!(
        (r.stop, r.rediscretized, r.rejected),
        (Some(StopReason::TauMin), false, Some(Rejection::EnergyIncrease))
    );
    // with a fresh evaluation the step is retried from the fresh energy and taken
    let mut fresh = StaleStart { bias: 0.1, fresh: true, evaluations: Default::default() };
    drop(flow);
    let mut flow = Flow::new(&mut fresh, start(), settings).unwrap();
    let j0 = flow.energy();
    let r = flow.step().unwrap();
    assert!(r.rediscretized && !r.accepted && r.stop.is_none(), "{r:?}");
    let j_fresh = flow.energy();
    assert!((j_fresh - (j0 + 0.1)).abs() < 1e-12, "{j0} → {j_fresh}");
    assert_eq!(flow.run(&AtomicBool::new(false), |_| {}).unwrap(), StopReason::MaxIterations);
    assert_eq!(flow.iteration(), 5);
    assert!(flow.energy() < j_fresh, "curve shortening shortens: {j_fresh} → {}", flow.energy());
}
