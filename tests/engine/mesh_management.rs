//! Mesh management of curves in the flow: regularization, adaptivity, topology.

use shapeflow::flow::{CurveManager, Flow, FlowSettings, MeshManager, StopReason};
use shapeflow::geometry::{circle, polygon, union, CurveMesh, CurveRemeshSettings, Point};
use shapeflow::problems::CurvatureFlow;
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

/// A dumbbell `x = 2 cos t, y = sin t (0.6 x² + neck)`, sampled non-uniformly in `t`.
fn dumbbell(n: usize, neck: f64, skew: f64) -> CurveMesh {
    let pts: Vec<Point<2>> = (0..n)
        .map(|k| {
            let u = k as f64 / n as f64;
            let t = 2.0 * PI * (u + skew * (2.0 * PI * u).sin() / (2.0 * PI));
            let x = 2.0 * t.cos();
            Point::<2>::new(x, t.sin() * (0.6 * x * x + neck))
        })
        .collect();
    polygon(&pts, None).unwrap()
}

fn manager(regularize: bool, adapt: bool, topology: bool, params: CurveRemeshSettings) -> Box<dyn MeshManager<2>> {
    Box::new(CurveManager { regularize, sweeps: 3, adapt, topology_changes: topology, params })
}

/// Runs curvature flow and returns the worst longest/shortest edge ratio seen.
fn worst_edge_ratio(mesh: CurveMesh, regularize: bool) -> (f64, f64) {
    let mut problem = CurvatureFlow { gamma: 1.0, lambda: 0.0 };
    let params = CurveManager::defaults_for(&mesh);
    let settings = FlowSettings {
        tau: 2e-4,
        end_time: Some(0.1),
        max_iterations: usize::MAX,
        tolerance: 0.0,
        ..FlowSettings::default()
    };
    let mut flow = Flow::new(&mut problem, mesh, settings).unwrap();
    if regularize {
        flow = flow.with_mesh_manager(manager(true, false, false, params));
    }
    let mut worst: f64 = 0.0;
    let stop = flow
        .run(&AtomicBool::new(false), |f| {
            let q = f.mesh().quality();
            worst = worst.max(q.max_edge / q.min_edge);
        })
        .unwrap();
    let q = flow.mesh().quality();
    eprintln!(
        "regularize={regularize}: stop {stop:?}, worst ratio {worst:.2}, final ratio {:.2}",
        q.max_edge / q.min_edge
    );
    (worst, q.max_edge / q.min_edge)
}

#[test]
fn regularization_keeps_a_nonuniform_dumbbell_regular() {
    let start = dumbbell(200, 0.15, 0.8);
    let q = start.quality();
    eprintln!("initial ratio {:.2}", q.max_edge / q.min_edge);
    let (with, with_final) = worst_edge_ratio(start.clone(), true);
    let (without, without_final) = worst_edge_ratio(start, false);
    assert!(with_final < 2.0, "with regularization the edges equalize: {with_final}");
    assert!(with <= q.max_edge / q.min_edge + 1e-9, "never worse than the start: {with}");
    assert!(
        without_final > 2.0 * with_final,
        "without regularization the sampling stays bad: {without_final} vs {with_final}"
    );
    assert!(without > q.max_edge / q.min_edge, "and degrades further: {without}");
}

fn run_with_topology(mesh: CurveMesh, lambda: f64, end: f64) -> Flow<'static, 2> {
    let problem: &'static mut CurvatureFlow = Box::leak(Box::new(CurvatureFlow { gamma: 1.0, lambda }));
    let params = CurveManager::defaults_for(&mesh);
    let settings = FlowSettings {
        tau: 1e-3,
        end_time: Some(end),
        max_iterations: usize::MAX,
        tolerance: 0.0,
        backtracking: false,
        ..FlowSettings::default()
    };
    let mut flow = Flow::new(problem, mesh, settings).unwrap().with_mesh_manager(manager(true, true, true, params));
    let stop = flow.run(&AtomicBool::new(false), |_| {}).unwrap();
    assert_eq!(stop, StopReason::EndTime);
    flow
}

fn component_areas(m: &CurveMesh) -> Vec<f64> {
    m.cycles()
        .iter()
        .map(|c| {
            (0..c.len())
                .map(|k| {
                    let (p, q) = (m.positions()[c[k]], m.positions()[c[(k + 1) % c.len()]]);
                    0.5 * (p.x * q.y - q.x * p.y)
                })
                .sum()
        })
        .collect()
}

#[test]
fn two_growing_circles_merge_into_one_curve() {
    let a = circle([-0.55, 0.0], 0.5, 96).unwrap();
    let b = circle([0.55, 0.0], 0.5, 96).unwrap();
    let start = union(&[a, b]).unwrap();
    // λ = −3: each circle grows with speed 3 − κ = 1 until they touch
    let flow = run_with_topology(start, -3.0, 0.15);
    let m = flow.mesh();
    let areas = component_areas(m);
    eprintln!("merged: components {}, areas {areas:?}", m.num_components());
    assert_eq!(m.num_components(), 1);
    assert!(areas[0] > 2.0 * PI * 0.5 * 0.5, "counter-clockwise and larger than both disks: {areas:?}");
}

#[test]
fn a_pinched_dumbbell_splits_into_two_curves() {
    let start = dumbbell(300, 0.04, 0.0);
    // λ = 3 closes the thin neck long before the lobes vanish
    let flow = run_with_topology(start, 3.0, 0.05);
    let m = flow.mesh();
    let areas = component_areas(m);
    eprintln!("split: components {}, areas {areas:?}", m.num_components());
    assert_eq!(m.num_components(), 2);
    assert!(areas.iter().all(|&a| a > 0.5), "both lobes counter-clockwise with their area: {areas:?}");
    assert!((areas[0] - areas[1]).abs() < 0.02 * areas[0], "symmetric lobes: {areas:?}");
}

#[test]
fn adaptivity_keeps_the_exact_circle_and_grades_an_ellipse() {
    // the shrinking circle of the engine tests, with every management switch on
    let start = circle([0.0, 0.0], 1.0, 256).unwrap();
    let params = CurveManager::defaults_for(&start);
    let h = 2.0 * PI / 256.0;
    let settings = FlowSettings {
        tau: 0.5 * h * h,
        end_time: Some(0.25),
        max_iterations: usize::MAX,
        tolerance: 0.0,
        step_control: None,
        ..FlowSettings::default()
    };
    let mut problem = CurvatureFlow { gamma: 1.0, lambda: 0.0 };
    let mut flow =
        Flow::new(&mut problem, start, settings).unwrap().with_mesh_manager(manager(true, true, true, params));
    flow.run(&AtomicBool::new(false), |_| {}).unwrap();
    let exact = 0.5f64.sqrt();
    let err = flow.mesh().positions().iter().map(|p| (p.norm() - exact).abs()).fold(0.0, f64::max);
    eprintln!("circle with management: error {err:e}, vertices {}", flow.mesh().num_vertices());
    assert!(err < 1e-3, "{err}");
    drop(flow);

    // a 4:1 ellipse sampled uniformly: refinement at the tips, coarsening on the flanks
    let start = shapeflow::geometry::ellipse([0.0, 0.0], [2.0, 0.5], 0.0, 200).unwrap();
    let mut params = CurveManager::defaults_for(&start);
    params.epsilon *= 0.3;
    let settings = FlowSettings { tau: 1e-4, max_iterations: 20, tolerance: 0.0, ..FlowSettings::default() };
    let mut flow =
        Flow::new(&mut problem, start, settings).unwrap().with_mesh_manager(manager(true, true, false, params));
    flow.run(&AtomicBool::new(false), |_| {}).unwrap();
    let m = flow.mesh();
    let mean_len = |pred: &dyn Fn(f64) -> bool| {
        let lens: Vec<f64> = m
            .elements()
            .iter()
            .filter(|e| pred(m.positions()[e[0]].x))
            .map(|e| (m.positions()[e[1]] - m.positions()[e[0]]).norm())
            .collect();
        lens.iter().sum::<f64>() / lens.len() as f64
    };
    let tips = mean_len(&|x: f64| x.abs() > 1.8);
    let flanks = mean_len(&|x: f64| x.abs() < 0.8);
    eprintln!("ellipse: {} vertices, mean edge at the tips {tips:.4}, on the flanks {flanks:.4}", m.num_vertices());
    assert!(flanks > 2.0 * tips, "fewer vertices on flat parts: tips {tips}, flanks {flanks}");
}

#[test]
fn shrinking_sphere_keeps_its_exact_solution_with_surface_management() {
    use shapeflow::flow::SurfaceManager;
    let start = shapeflow::geometry::icosphere([0.0; 3], 1.0, 4).unwrap();
    let (params, pinch) = SurfaceManager::defaults_for(&start);
    let mgr = SurfaceManager {
        regularize: true,
        sweeps: 3,
        adapt: true,
        params,
        pinch_curvature: Some(pinch),
        surgery: None,
        declined: None,
    };
    let settings = FlowSettings {
        tau: 2.5e-4,
        end_time: Some(0.1),
        max_iterations: usize::MAX,
        tolerance: 0.0,
        step_control: None,
        ..FlowSettings::default()
    };
    let mut problem = CurvatureFlow { gamma: 1.0, lambda: 0.0 };
    let mut flow = Flow::new(&mut problem, start, settings).unwrap().with_mesh_manager(Box::new(mgr));
    assert_eq!(flow.run(&AtomicBool::new(false), |_| {}).unwrap(), StopReason::EndTime);
    let exact = (1.0f64 - 0.4).sqrt();
    let err = flow.mesh().positions().iter().map(|p| (p.norm() - exact).abs()).fold(0.0, f64::max);
    let q = flow.mesh().quality();
    eprintln!(
        "sphere with management: error {err:e}, vertices {}, angles [{:.1}, {:.1}]",
        flow.mesh().num_vertices(),
        q.min_angle_deg,
        q.max_angle_deg
    );
    assert!(err < 5e-3, "{err}");
    assert!(q.min_angle_deg > 30.0);
}

/// Objects kept apart (`keep_apart`, a segmentation's separate objects): when a
/// pass would make two of them cross, those two only have their tiny segments
/// collapsed, and the others are still managed. Before, the whole pass was
/// dropped, so that a segment shrinking beside a contact was never collapsed and
/// the step control halved `τ` at every step until the run stopped `converged`
/// on vanishing steps.
#[test]
fn a_pass_that_would_make_two_objects_cross_still_manages_the_others() {
    use shapeflow::flow::Managed;
    use shapeflow::geometry::manage_curve;
    let p = |x: f64, y: f64| Point::<2>::new(x, y);
    // a block with a notch on top, its bottom off-centre, and a wedge in the notch
    // whose tip is just above the notch's bottom
    let block =
        polygon(&[p(0.0, 0.0), p(4.0, 0.0), p(4.0, 4.0), p(2.6, 4.0), p(1.7, 2.5), p(1.4, 4.0), p(0.0, 4.0)], None)
            .unwrap();
    // (with a segment of 1e-5 at its top)
    let wedge = polygon(&[p(1.7, 2.501), p(2.3, 3.9), p(2.29999, 3.9), p(1.6, 3.9)], None).unwrap();
    // far away, a circle with one segment of 1e-4
    let mut pts: Vec<Point<2>> = (0..40)
        .map(|k| {
            let t = 2.0 * PI * k as f64 / 40.0;
            p(10.0 + t.cos(), 10.0 + t.sin())
        })
        .collect();
    pts.insert(1, p(11.0, 10.0001));
    let ring = polygon(&pts, None).unwrap();
    let mesh = union(&[block.clone(), wedge.clone(), ring.clone()]).unwrap();
    let mut params = CurveManager::defaults_for(&mesh);
    params.keep_apart = true;
    // the pass on every loop makes the block and the wedge cross
    let (all, _) = manage_curve(&mesh, &params, true, 3).unwrap();
    let all = all.unwrap();
    assert!(!all.crossings_between_components(&all.crossings()).is_empty());
    let mut m = CurveManager { regularize: true, sweeps: 3, adapt: true, topology_changes: true, params };
    let out = match m.manage(&mesh).unwrap() {
        Managed::Moved(x) | Managed::Remeshed(x) => x,
        _ => panic!("the ring is managed"),
    };
    assert!(out.crossings_between_components(&out.crossings()).is_empty());
    let (label, count) = out.component_labels();
    assert_eq!(count, 3);
    let points = |c: usize| -> Vec<Point<2>> {
        out.positions().iter().zip(&label).filter(|(_, &l)| l == c).map(|(x, _)| *x).collect()
    };
    assert_eq!(points(0), block.positions().to_vec());
    // the wedge's tiny segment is collapsed to its midpoint, the rest as it was
    let w = wedge.positions();
    assert_eq!(points(1), vec![w[0], 0.5 * (w[1] + w[2]), w[3]]);
    assert!(points(2).len() < ring.num_vertices(), "the ring's short segment is collapsed");
}

/// Surfaces kept apart (a segmentation's touching objects): where the
/// adaptation would carry a triangle through a close sheet, it is made again
/// with the vertices there frozen, and the rest of the surface is still
/// adapted. A unit sphere (edges 0.62, longer than `h_max`) has a small ball
/// beside the midpoint of one edge, between the chord and the sphere: that
/// edge's split, lifted onto the sphere, would enter the ball. Before, the whole
/// adaptation was dropped, and a sliver anywhere that only the adaptation
/// removes held every later step (the nuclei volume crawled at `τ` ≈ 1e-7).
#[test]
fn an_adaptation_that_would_meet_a_close_sheet_still_adapts_the_rest() {
    use shapeflow::flow::{Managed, SurfaceManager};
    use shapeflow::geometry::{
        adapt_surface, icosphere, surface_intersections, Mesh, PatchSearch, SurfaceRemeshSettings,
    };
    let sphere = icosphere([0.0; 3], 1.0, 1).unwrap();
    let [a, b, _] = sphere.elements()[0];
    let (pa, pb) = (sphere.positions()[a], sphere.positions()[b]);
    let mid = (pa + pb) * 0.5;
    let sagitta = 1.0 - mid.norm();
    let r = 0.05;
    let centre = mid.normalize() * (mid.norm() + 0.5 * sagitta + r);
    let ball = icosphere([centre.x, centre.y, centre.z], r, 1).unwrap();
    let mut x = sphere.positions().to_vec();
    x.extend(ball.positions());
    let n = sphere.num_vertices();
    let mut triangles = sphere.elements().to_vec();
    triangles.extend(ball.elements().iter().map(|t| t.map(|v| v + n)));
    let mesh = Mesh::<3>::new(x, triangles).unwrap();
    assert!(surface_intersections(mesh.positions(), mesh.elements(), 1).is_empty(), "the two start apart");
    let params = SurfaceRemeshSettings { epsilon: 0.01, h_min: 1e-3, h_max: 0.5, max_angle_deg: 120.0 };
    let free = adapt_surface(&mesh, &params).unwrap();
    assert!(!surface_intersections(free.positions(), free.elements(), 1).is_empty(), "the free adaptation meets");

    let mut manager = SurfaceManager {
        regularize: false,
        sweeps: 0,
        adapt: true,
        params,
        pinch_curvature: None,
        surgery: None,
        declined: None,
    };
    let Managed::Remeshed(m) = manager.manage_searched(&mesh, &mut PatchSearch::default()).unwrap() else {
        panic!("the adaptation was not taken")
    };
    assert!(surface_intersections(m.positions(), m.elements(), usize::MAX).is_empty(), "the result meets");
    // the sphere's edges split away from the ball (120 edges; a handful near it kept)
    let (component, _) = m.component_labels();
    let first = m.positions().iter().position(|p| *p == pa).expect("the edge's end is kept");
    let sphere_vertices: Vec<Point<3>> =
        m.positions().iter().zip(&component).filter(|(_, &c)| c == component[first]).map(|(p, _)| *p).collect();
    assert!(sphere_vertices.len() > n + 100, "{} sphere vertices from {n}", sphere_vertices.len());
    // and the edge beside the ball kept whole: its two ends, and no vertex between
    assert!(sphere_vertices.contains(&pb));
    let between = sphere_vertices.iter().filter(|p| (**p - mid).norm() < 0.1 || (**p - centre).norm() < r).count();
    assert_eq!(between, 0, "no sphere vertex at the edge's midpoint");
}
