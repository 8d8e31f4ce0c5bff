//! Optimal shape design (paper §4.3): shape derivative against finite differences,
//! and the paper's experiments.

mod merging;

use shapeflow::bulk::{DesignDomain, MeshingOptions, Polygon};
use shapeflow::flow::{shape_derivative, Flow, MeshManager, Problem};
use shapeflow::geometry::{circle, CurveMesh, Point};
use shapeflow::jobs::{parse_spec, prepare, run_prepared, AnyMesh, JobOutcome, PreparedJob, ProblemKind, RunEvents};
use shapeflow::problems::{DesignRun, GradientKind, ShapeDesign, Target};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

fn circle_polygon(what: &str, r: f64, n: usize) -> Polygon {
    Polygon::from_curve(what, circle([0.0, 0.0], r, n)).unwrap()
}

/// Paper §4.3.2: Σ the circle of radius 3, D = {2 ≤ |x| ≤ 2.5}, z_g = log(3/|x|).
fn test1(h: f64, curve_spacing: f64) -> ShapeDesign {
    let n = |r: f64| (2.0 * PI * r / h).ceil() as usize;
    let domain = DesignDomain::new(
        circle_polygon("outer", 3.0, n(3.0)),
        circle_polygon("control.inner", 2.0, n(2.0)),
        circle_polygon("control.outer", 2.5, n(2.5)),
    )
    .unwrap();
    let meshing = MeshingOptions::for_domain(&domain, curve_spacing);
    ShapeDesign::new(
        Arc::new(domain),
        Target::LogRadial { center: Point::<2>::zeros(), radius: 3.0 },
        0.0,
        true,
        1e-6,
        meshing,
    )
}

fn moved(mesh: &CurveMesh, field: &[Point<2>], d: f64) -> CurveMesh {
    mesh.with_positions(mesh.positions().iter().zip(field).map(|(x, v)| x + v * d).collect())
}

#[test]
fn shape_derivative_matches_finite_differences() {
    let n = 256;
    let mesh = circle([0.3, 0.2], 0.8, n).unwrap();
    let c = Point::<2>::new(0.3, 0.2);
    let fields: [(&str, Vec<Point<2>>); 3] = [
        ("translation x", vec![Point::<2>::new(1.0, 0.0); n]),
        ("translation y", vec![Point::<2>::new(0.0, 1.0); n]),
        ("dilation", mesh.positions().iter().map(|x| x - c).collect()),
    ];
    // the paper's formula: to discretization error; the discrete gradient: exact for
    // the bulk mesh that follows the curve (errors O(d²) of the central differences)
    for (kind, bound) in [(GradientKind::Continuous, 1e-2), (GradientKind::Discrete, 1e-4)] {
        let mut design = test1(0.05, 2.0 * PI * 0.8 / n as f64);
        design.gradient = kind;
        let mut problem = design.start();
        for (name, v) in &fields {
            let exact = shape_derivative(&mut problem, &mesh, v).unwrap();
            let d = 1e-3;
            let fd = (problem.energy(&moved(&mesh, v, d)).unwrap() - problem.energy(&moved(&mesh, v, -d)).unwrap())
                / (2.0 * d);
            let rel = (fd - exact).abs() / exact.abs();
            assert!(rel < bound, "{kind:?} {name}: dJ = {exact:e}, finite differences {fd:e}, relative error {rel:e}");
        }
    }
}

/// The exact discrete gradient against central differences, vertex by vertex, on a
/// curve whose bulk mesh follows it.
#[test]
fn discrete_sensitivity_is_exact() {
    let n = 96;
    let mut problem = test1(0.1, 2.0 * PI * 0.8 / n as f64).start();
    let mesh = circle([0.3, 0.2], 0.8, n).unwrap();
    let base = problem.solve(&mesh).unwrap();
    // fix the base mesh that trial curves follow
    shape_derivative(&mut problem, &mesh, &vec![Point::<2>::zeros(); n]).unwrap();
    let scale = base.sensitivity.iter().fold(0.0f64, |m, g| m.max(g.norm()));
    for k in [0, 17, 50] {
        for dir in [Point::<2>::new(1.0, 0.0), Point::<2>::new(0.0, 1.0)] {
            let mut v = vec![Point::<2>::zeros(); n];
            v[k] = dir;
            let h = 1e-6;
            let fd = (problem.energy(&moved(&mesh, &v, h)).unwrap() - problem.energy(&moved(&mesh, &v, -h)).unwrap())
                / (2.0 * h);
            let exact = base.sensitivity[k].dot(&dir);
            assert!((fd - exact).abs() < 1e-6 * scale, "vertex {k} {dir:?}: {fd:e} vs {exact:e} (largest {scale:e})");
        }
    }
}

#[test]
fn the_unit_circle_is_optimal_in_test_1() {
    let n = 128;
    let mut problem = test1(0.05, 2.0 * PI / n as f64).start();
    let mesh = circle([0.0, 0.0], 1.0, n).unwrap();
    let j = problem.energy(&mesh).unwrap();
    assert!(j < 1e-6, "J(unit circle) = {j:e}");
    // G ≈ 0: the shape derivative along any field is tiny compared with an off-centre circle's
    let dilation: Vec<Point<2>> = mesh.positions().to_vec();
    let translation = vec![Point::<2>::new(1.0, 0.0); n];
    for v in [&dilation, &translation] {
        let d = shape_derivative(&mut problem, &mesh, v).unwrap();
        assert!(d.abs() < 1e-4, "dJ = {d:e}");
    }
    let sol = problem.solve(&mesh).unwrap();
    let pmax = sol.p.iter().fold(0.0f64, |m, p| m.max(p.abs()));
    assert!(pmax < 1e-4, "max |p| on Γ = {pmax:e}");
    // y = log 3 on the unit circle
    for y in &sol.y {
        assert!((y - 3f64.ln()).abs() < 2e-3, "y = {y}");
    }
}

const TEST1: &str = r#"{"problem": {"type": "shape_design",
    "outer": {"shape": "circle", "radius": 3.0},
    "control": {"inner": {"shape": "circle", "radius": 2.0}, "outer": {"shape": "circle", "radius": 2.5}},
    "target": {"type": "log_radial", "radius": 3.0}},
  "initial": {"shape": "ellipse", "center": [0.5, 0.7], "semi_axes": [0.4, 0.25], "resolution": 64},
  "flow": {"scalar_product": "PRODUCT", "max_iterations": ITERATIONS, "tolerance": 0}}"#;

fn prepared(spec: &str) -> PreparedJob {
    prepare(parse_spec(spec).unwrap(), &HashMap::new()).unwrap()
}

struct History(Vec<f64>);
impl RunEvents for History {
    fn progress(&mut self, p: &shapeflow::flow::Progress) {
        self.0.push(p.energy);
    }
}

/// Area, area centroid and the range of the distance of the vertices from it.
fn roundness(mesh: &CurveMesh) -> (f64, Point<2>, f64, f64) {
    let x = mesh.positions();
    let (mut a, mut c) = (0.0, Point::<2>::zeros());
    for &[i, j] in mesh.elements() {
        let cr = x[i].x * x[j].y - x[j].x * x[i].y;
        a += 0.5 * cr;
        c += (x[i] + x[j]) * cr / 6.0;
    }
    c /= a;
    let r = x.iter().map(|p| (p - c).norm());
    let (lo, hi) = r.fold((f64::INFINITY, 0.0f64), |(lo, hi), r| (lo.min(r), hi.max(r)));
    (a, c, lo, hi)
}

#[test]
fn h1_flow_from_an_ellipse_approaches_the_unit_circle() {
    let job = prepared(&TEST1.replace("PRODUCT", "h1_newton").replace("ITERATIONS", "300"));
    let mut h = History(Vec::new());
    let out: JobOutcome = run_prepared(&job, None, &AtomicBool::new(false), &mut h).unwrap();
    let (j0, j1) = (h.0[0], *h.0.last().unwrap());
    assert!(j1 < 1e-4 * j0, "J {j0:e} → {j1:e}");
    // every step decreases J (backtracking); re-evaluating J after the curve is
    // regularized or remeshed moves it by the discretization error, which near the
    // optimum is a sizeable fraction of J itself (up to ~30 % at J ~ 1e-7)
    for w in h.0.windows(2) {
        assert!(w[1] <= 1.1 * w[0] + 1e-4 * j0, "J increased: {} → {}", w[0], w[1]);
    }
    let AnyMesh::Curve(mesh) = &job.mesh else { unreachable!() };
    let last: CurveMesh = out.last.mesh.to_mesh::<2>().unwrap();
    let (area, c, rmin, rmax) = roundness(&last);
    assert!(last.num_components() == 1 && mesh.num_components() == 1);
    assert!((area - PI).abs() < 0.05 * PI, "area {area}");
    assert!(c.norm() < 0.03, "centroid {c:?}");
    assert!(rmin > 0.9 && rmax < 1.1, "radius between {rmin} and {rmax}");
}

/// Per vertex: `|θ_i − ½(θ_{i−1} + θ_{i+1})|` (θ the turning angles, a mesh-level
/// oscillation indicator) and `p`.
fn oscillation(problem: &mut DesignRun, mesh: &CurveMesh) -> Vec<(f64, f64)> {
    let sol = problem.solve(mesh).unwrap();
    let mut out = Vec::new();
    for cyc in mesh.cycles() {
        let n = cyc.len();
        let x = |k: usize| mesh.positions()[cyc[k % n]];
        let theta: Vec<f64> = (0..n)
            .map(|k| {
                let (u, v) = (x(k + n) - x(k + n - 1), x(k + 1) - x(k));
                (u.x * v.y - u.y * v.x).atan2(u.dot(&v))
            })
            .collect();
        for k in 0..n {
            let o = (theta[k] - 0.5 * (theta[(k + n - 1) % n] + theta[(k + 1) % n])).abs();
            out.push((o, sol.p[cyc[k]]));
        }
    }
    out
}

/// Paper Figure 4: the L2 flow is backward parabolic where `p < 0` and oscillates at
/// the mesh level there; the weighted H1 flow of eq. (84) does not.
#[test]
fn l2_flow_oscillates_where_p_is_negative() {
    let mut mean_osc = Vec::new();
    for product in ["l2", "h1_newton"] {
        let job = prepared(&TEST1.replace("PRODUCT", product).replace("ITERATIONS", "100"));
        let ProblemKind::ShapeDesign(problem) = &job.problem else { unreachable!() };
        let AnyMesh::Curve(mesh) = &job.mesh else { unreachable!() };
        let mut run = problem.start();
        let mut flow = Flow::new(&mut run, mesh.clone(), job.settings.clone()).unwrap();
        if let Some(m) = job.curve_manager {
            flow = flow.with_mesh_manager(Box::new(m) as Box<dyn MeshManager<2>>);
        }
        for _ in 0..10 {
            flow.step().unwrap();
        }
        // the run keeps the flow's last solve and the bulk mesh it follows
        let mesh = flow.mesh().clone();
        drop(flow);
        let o = oscillation(&mut run, &mesh);
        let neg: Vec<f64> = o.iter().filter(|x| x.1 < 0.0).map(|x| x.0).collect();
        assert!(neg.len() >= 10, "{product}: p < 0 on {} of {} vertices", neg.len(), o.len());
        mean_osc.push(neg.iter().sum::<f64>() / neg.len() as f64);
    }
    let (l2, h1) = (mean_osc[0], mean_osc[1]);
    // L2: turning angles alternate by tenths of a radian from vertex to vertex
    assert!(l2 > 0.1, "L2 oscillation {l2}");
    assert!(l2 > 10.0 * h1, "L2 {l2} vs H1 {h1}");
}

/// Paper §4.3.3: the square ring, z_g = 0.45, Γ the circle of radius 0.5. The paper
/// reports ∫_D (y − z_g)² = 0.97481 at the start; ours has the ½.
#[test]
fn square_ring_initial_energy_matches_the_paper() {
    let spec = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/design_square.json")).unwrap();
    let job = prepared(&spec);
    let ProblemKind::ShapeDesign(problem) = &job.problem else { unreachable!() };
    let AnyMesh::Curve(mesh) = &job.mesh else { unreachable!() };
    let j = problem.start().energy(mesh).unwrap();
    let paper = 0.97481 / 2.0;
    assert!((j - paper).abs() < 5e-3 * paper, "J = {j} vs {paper}");
}

#[test]
fn bad_shape_design_specs_name_the_field() {
    let base: serde_json::Value =
        serde_json::from_str(&TEST1.replace("PRODUCT", "h1_newton").replace("ITERATIONS", "10")).unwrap();
    let nested = serde_json::json!({"shape": "union", "parts": [
        {"shape": "circle", "radius": 1.0, "resolution": 64},
        {"shape": "circle", "radius": 0.5, "resolution": 32}]});
    let cases: [(&str, serde_json::Value, &str); 8] = [
        ("/problem/control/inner/radius", (-2.0).into(), "problem.control.inner.radius"),
        ("/problem/control/inner/radius", 2.7.into(), "problem.control.inner"),
        ("/problem/target/center", serde_json::json!([2.2, 0.0]), "problem.target.center"),
        ("/problem/target/color", "red".into(), "problem.target.color"),
        ("/problem/gamma", (-1.0).into(), "problem.gamma"),
        ("/initial/semi_axes", serde_json::json!([2.2, 0.3]), "initial"),
        ("/initial", serde_json::json!({"shape": "sphere", "radius": 1.0}), "initial"),
        // one curve inside another: the ring between them has no Dirichlet boundary
        ("/initial", nested, "initial"),
    ];
    for (pointer, value, field) in cases {
        let mut spec = base.clone();
        let (parent, key) = pointer.rsplit_once('/').unwrap();
        spec.pointer_mut(if parent.is_empty() { "" } else { parent }).unwrap()[key] = value;
        let err = parse_spec(&spec.to_string()).and_then(|s| prepare(s, &HashMap::new()).map(|_| ())).unwrap_err();
        assert_eq!(err.field, field, "{pointer}: {err}");
    }
}

/// Paper Figure 7: `z_g = 0.45 + 0.4 cos 6θ` on the ring of Test 1, from a small
/// centred circle (`examples/design_polar.json`: τ = 0.2, no mesh management): J
/// keeps decreasing for 1,000 iterations and the curve takes the six-fold structure
/// of `z_g`, reaching out (larger radius) where `z_g` is large.
#[test]
fn polar_target_j_keeps_decreasing_into_a_six_fold_shape() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/design_polar.json")).unwrap();
    let mut spec: serde_json::Value = serde_json::from_str(&text).unwrap();
    spec["flow"]["max_iterations"] = 1000.into();
    let job = prepared(&spec.to_string());
    let mut h = History(Vec::new());
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut h).unwrap();
    let j = &h.0;
    assert_eq!(j.len(), 1001, "stopped early: {:?}", out.stop);
    // measured: J decreases at every step, from 0.6198 to 0.31577 (the paper:
    // 0.32786 at k = 960, 0.31461 at k = 1,600; ours 0.31483 at 1,600). A step on a
    // fresh bulk mesh after backtracking failed on the followed one (driver item 5)
    // would show as one rise of ~5e-5 (measured at τ = 0.3, 0.5); none occurs here.
    let rises: Vec<(usize, f64)> = (1..j.len()).filter(|&k| j[k] > j[k - 1]).map(|k| (k, j[k] - j[k - 1])).collect();
    assert!(rises.len() <= 1 && rises.iter().all(|r| r.1 < 1e-4), "J rose: {rises:?}");
    for k in (100..=1000).step_by(100) {
        assert!(
            j[k] < j[k - 100] - 1e-5,
            "J did not decrease from iteration {} to {k}: {:?}",
            k - 100,
            &j[k - 100..=k]
        );
    }
    assert!(j[1000] < 0.3160 && j[1000] > 0.3140, "J after 1,000 iterations: {}", j[1000]);
    let last: CurveMesh = out.last.mesh.to_mesh::<2>().unwrap();
    assert_eq!(last.num_components(), 1);
    // Fourier modes of r(θ) around the origin, by the midpoint rule in θ
    let x = last.positions();
    let mode = |k: f64| -> (f64, f64) {
        let (mut c, mut s, mut total) = (0.0, 0.0, 0.0);
        for &[a, b] in last.elements() {
            let (ta, tb) = (x[a].y.atan2(x[a].x), x[b].y.atan2(x[b].x));
            let dt = (tb - ta + 3.0 * PI).rem_euclid(2.0 * PI) - PI;
            let (t, r) = (ta + 0.5 * dt, 0.5 * (x[a].norm() + x[b].norm()));
            c += r * (k * t).cos() * dt;
            s += r * (k * t).sin() * dt;
            total += dt;
        }
        (c / total, s / total)
    };
    let (c6, s6) = mode(6.0);
    let others = [1.0, 2.0, 3.0, 4.0, 5.0, 7.0, 8.0, 9.0, 10.0, 11.0].map(|k| {
        let (c, s) = mode(k);
        c.hypot(s)
    });
    let worst = others.iter().fold(0.0f64, |m, a| m.max(*a));
    assert!(c6 > 0.02 && c6 > 5.0 * worst, "mode 6: cos {c6:.4} sin {s6:.4}; largest other mode {worst:.4}");
    assert!(s6.abs() < 0.2 * c6, "mode 6 out of phase with cos 6θ: cos {c6:.4} sin {s6:.4}");
}
