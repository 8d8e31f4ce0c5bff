//! Exact solutions, convergence orders and conserved quantities of the engine.

use shapeflow::flow::{
    Flow, FlowSettings, Problem, ProblemError, Rejection, ScalarProduct, ShapeGradient, SolverKind, StopReason,
    SurfaceState,
};
use shapeflow::geometry::{circle, ellipse, ellipsoid, icosphere, Mesh};
use shapeflow::problems::{CurvatureFlow, SurfaceDiffusion};
use std::sync::atomic::AtomicBool;

fn radius_error<const D: usize>(mesh: &Mesh<D>, exact: f64) -> f64 {
    mesh.positions().iter().map(|p| (p.norm() - exact).abs()).fold(0.0, f64::max)
}

fn mcf_settings(tau: f64, end: f64, solver: SolverKind) -> FlowSettings {
    FlowSettings {
        scalar_product: ScalarProduct::L2,
        solver,
        tau,
        max_iterations: usize::MAX,
        end_time: Some(end),
        tolerance: 0.0,
        step_control: None,
        ..FlowSettings::default()
    }
}

fn shrink_circle(n: usize, solver: SolverKind) -> f64 {
    let h = 2.0 * std::f64::consts::PI / n as f64;
    let mut problem = CurvatureFlow { gamma: 1.0, lambda: 0.0 };
    let mut flow =
        Flow::new(&mut problem, circle([0.0, 0.0], 1.0, n).unwrap(), mcf_settings(0.5 * h * h, 0.25, solver)).unwrap();
    let stop = flow.run(&AtomicBool::new(false), |_| {}).unwrap();
    assert_eq!(stop, StopReason::EndTime);
    assert!((flow.time() - 0.25).abs() < 1e-12);
    radius_error(flow.mesh(), (1.0f64 - 2.0 * 0.25).sqrt())
}

fn order(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

#[test]
fn circle_curve_shortening_exact_solution_and_order() {
    let errs: Vec<f64> = [32, 64, 128, 256].iter().map(|&n| shrink_circle(n, SolverKind::Lumped)).collect();
    let orders = order(&errs);
    eprintln!("circle errors {errs:?} orders {orders:?}");
    assert!(errs[3] < 1e-3, "error {} with 256 vertices", errs[3]);
    assert!(orders.iter().all(|&o| o >= 1.8), "orders {orders:?}");
}

fn shrink_sphere(level: u32, tau: f64, solver: SolverKind) -> f64 {
    let mut problem = CurvatureFlow { gamma: 1.0, lambda: 0.0 };
    let mut flow =
        Flow::new(&mut problem, icosphere([0.0; 3], 1.0, level).unwrap(), mcf_settings(tau, 0.1, solver)).unwrap();
    let stop = flow.run(&AtomicBool::new(false), |_| {}).unwrap();
    assert_eq!(stop, StopReason::EndTime);
    radius_error(flow.mesh(), (1.0f64 - 4.0 * 0.1).sqrt())
}

#[test]
fn sphere_mean_curvature_flow_exact_solution_and_order() {
    // h halves per level; τ ∝ h²
    let errs: Vec<f64> =
        [(2, 4e-3), (3, 1e-3), (4, 2.5e-4)].iter().map(|&(l, t)| shrink_sphere(l, t, SolverKind::Lumped)).collect();
    let orders = order(&errs);
    eprintln!("sphere errors {errs:?} orders {orders:?}");
    assert!(errs[2] < 5e-3, "error {} on 2562 vertices", errs[2]);
    assert!(orders.iter().all(|&o| o >= 1.5), "orders {orders:?}");
}

#[test]
fn lumped_and_consistent_paths_agree_to_discretization_error() {
    // circle: both paths converge to the exact solution; their difference is of the
    // size of the discretization error and shrinks with h
    let mut diffs = Vec::new();
    for n in [32, 64] {
        let a = shrink_circle(n, SolverKind::Lumped);
        let b = shrink_circle(n, SolverKind::Consistent);
        eprintln!("n={n}: lumped {a:e} consistent {b:e}");
        assert!(b < 4.0 * a.max(1e-4), "consistent error {b} vs lumped {a}");
        diffs.push(b);
    }
    assert!(diffs[1] < diffs[0] / 3.0, "consistent path converges: {diffs:?}");
    let a = shrink_sphere(3, 1e-3, SolverKind::Lumped);
    let b = shrink_sphere(3, 1e-3, SolverKind::Consistent);
    eprintln!("sphere level 3: lumped {a:e} consistent {b:e}");
    assert!(b < 5e-3 && a < 5e-3);
}

mod driver;
mod surface_diffusion;
