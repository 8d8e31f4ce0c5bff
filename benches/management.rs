//! Cost of curve mesh management per step (intersection check by spatial hashing,
//! refinement/coarsening, one regularization sweep) next to the cost of the L2 step
//! itself (assembly + Schur solve), on circles of 10k and 100k vertices whose
//! sampling is perturbed so that every part has work to do.
//! `cargo bench --bench management`.

use shapeflow::fem::{Matrices, Pattern};
use shapeflow::flow::{
    CurveManager, Flow, FlowError, FlowSettings, LinearSystem, Managed, MeshManager, ProductWeights, SemiImplicitStep,
    SolverKind, SurfaceManager, WatchedCurveManager,
};
use shapeflow::geometry::{icosphere, polygon, CurveMesh, Point};
use shapeflow::problems::CurvatureFlow;
use std::hint::black_box;
use std::sync::{Arc, Mutex};
use std::time::Instant;

#[path = "common/mod.rs"]
mod common;
#[path = "management/surgery.rs"]
mod surgery;
use common::time_it;

/// Mean time of one L2 step (assembly + Schur solve) on `mesh`, and of its solve alone.
fn l2_step_time<const D: usize>(mesh: &shapeflow::geometry::Mesh<D>) -> (f64, f64) {
    let n = mesh.num_vertices();
    let pattern = Pattern::new(n, mesh.elements());
    let mut m = Matrices::assemble(mesh, &pattern);
    let (g, f) = (vec![1.0; n], vec![0.0; n]);
    let mut step = SemiImplicitStep::new(SolverKind::Lumped);
    let mut solve = |m: &Matrices<D>, ax: &[Point<D>]| {
        let product = ProductWeights::L2;
        let sys = LinearSystem {
            mesh,
            pattern: &pattern,
            matrices: m,
            ax,
            g: &g,
            f: &f,
            product: &product,
            tau: 1e-4,
            bending: 0.0,
            limits: None,
        };
        black_box(step.velocity(&sys).unwrap());
    };
    let whole = time_it(0.5, || {
        m.assemble_into(mesh, &pattern, false);
        let ax = m.stiffness_times_positions(mesh, &pattern);
        solve(&m, &ax);
    });
    m.assemble_into(mesh, &pattern, false);
    let ax = m.stiffness_times_positions(mesh, &pattern);
    let alone = time_it(0.5, || solve(&m, &ax));
    (whole, alone)
}

/// One table row: times in seconds, printed in ms, with the two ratios.
fn print_row(n: usize, t_step: f64, t_solve: f64, t_manage: f64) {
    let ms = |t: f64| t * 1e3;
    println!(
        "| {n} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} |",
        ms(t_step),
        ms(t_solve),
        ms(t_manage),
        t_manage / t_step,
        t_manage / t_solve
    );
}

/// Seconds spent, calls, calls that re-meshed, full crossing checks, skipped ones.
type Spent = (f64, usize, usize, usize, usize);

/// A curve manager that adds up the time spent in it.
struct Timed {
    inner: WatchedCurveManager,
    spent: Arc<Mutex<Spent>>,
}

impl MeshManager<2> for Timed {
    fn manage(&mut self, mesh: &CurveMesh) -> Result<Managed<2>, FlowError> {
        let start = Instant::now();
        let out = self.inner.manage(mesh);
        let mut spent = self.spent.lock().unwrap();
        spent.0 += start.elapsed().as_secs_f64();
        spent.1 += 1;
        if matches!(out, Ok(Managed::Remeshed(_))) {
            spent.2 += 1;
        }
        (spent.3, spent.4) = (self.inner.watch.full_checks, self.inner.watch.skipped);
        out
    }
}

/// Curvature flow (L2, default settings, `tau` 1e-4) of the perturbed curve for
/// `steps` steps with the default curve management: mean seconds per step of the
/// management, of the whole step (management included), and the mesh at the end.
fn curve_flow_run(mesh: &CurveMesh, steps: usize) -> (f64, f64, CurveMesh) {
    let mut problem = CurvatureFlow { gamma: 1.0, lambda: 0.0 };
    let settings = FlowSettings { tau: 1e-4, tolerance: 0.0, ..FlowSettings::default() };
    let spent = Arc::new(Mutex::new((0.0, 0, 0, 0, 0)));
    let manager = CurveManager {
        regularize: true,
        sweeps: 1,
        adapt: true,
        topology_changes: true,
        params: CurveManager::defaults_for(mesh),
    };
    let mut flow = Flow::new(&mut problem, mesh.clone(), settings)
        .unwrap()
        .with_mesh_manager(Box::new(Timed { inner: manager.watched(), spent: spent.clone() }));
    flow.step().unwrap(); // warm-up: the first pass settles the sampling
    let first_checks = spent.lock().unwrap().3;
    *spent.lock().unwrap() = (0.0, 0, 0, 0, 0);
    let start = Instant::now();
    for _ in 0..steps {
        assert!(flow.step().unwrap().stop.is_none());
    }
    let per_step = start.elapsed().as_secs_f64() / steps as f64;
    let (total, calls, remeshed, full, skipped) = *spent.lock().unwrap();
    assert_eq!(calls, steps);
    eprintln!(
        "curvature-flow run: new connectivity after {remeshed} of {steps} steps; crossing checks: {} full, {skipped} \
         answered by the certificate",
        full - first_checks
    );
    (total / steps as f64, per_step, flow.mesh().clone())
}

/// The positions of `steps` accepted steps of a curvature flow (`τ` fixed, no
/// mesh management: one connectivity) of an ellipsoid of semi-axes 1, 0.8, 0.6 with
/// the vertices of the level-6 icosphere (40,962), the first one included.
fn ellipsoid_states(tau: f64, steps: usize) -> Vec<Vec<Point<3>>> {
    let mesh = shapeflow::geometry::ellipsoid([0.0; 3], [1.0, 0.8, 0.6], 6).unwrap();
    let mut problem = CurvatureFlow { gamma: 1.0, lambda: 0.0 };
    let settings = FlowSettings { tau, tolerance: 0.0, step_control: None, ..FlowSettings::default() };
    let mut states = vec![mesh.positions().to_vec()];
    let mut flow = Flow::new(&mut problem, mesh, settings).unwrap();
    for _ in 0..steps {
        let report = flow.step().unwrap();
        assert!(report.stop.is_none() && report.accepted);
        states.push(flow.mesh().positions().to_vec());
    }
    states
}

fn main() {
    shapeflow::tune_allocator();
    println!("| curve vertices | L2 step (ms) | of which solve (ms) | management (ms) | management / step | management / solve |");
    println!("|---:|---:|---:|---:|---:|---:|");
    for n in [10_000usize, 100_000].into_iter().filter(|_| std::env::var_os("SURFACES_ONLY").is_none()) {
        let pts: Vec<Point<2>> = (0..n)
            .map(|k| {
                let u = k as f64 / n as f64;
                let t = 2.0 * std::f64::consts::PI * (u + 0.05 * (2.0 * std::f64::consts::PI * u).sin() / 6.3);
                let r = 1.0 + 0.05 * (7.0 * t).cos();
                Point::<2>::new(r * t.cos(), r * t.sin())
            })
            .collect();
        let mesh = polygon(&pts, None).unwrap();
        let (t_step, t_solve) = l2_step_time(&mesh);
        let mut manager = CurveManager {
            regularize: true,
            sweeps: 1,
            adapt: true,
            topology_changes: true,
            params: CurveManager::defaults_for(&mesh),
        };
        let t_manage = time_it(0.5, || {
            black_box(manager.manage(&mesh).unwrap());
        });
        let t_int = time_it(0.5, || {
            black_box(shapeflow::geometry::find_segment_intersections(mesh.positions(), mesh.elements()));
        });
        let params = manager.params;
        let t_adapt = time_it(0.5, || {
            black_box(shapeflow::geometry::adapt_curve(&mesh, &params).unwrap());
        });
        let t_reg = time_it(0.5, || {
            black_box(shapeflow::geometry::regularize_curve(&mesh, 1, Some(&params)));
        });
        eprintln!(
            "n={n}: intersections {:.3} ms, adapt {:.3} ms, regularize {:.3} ms",
            t_int * 1e3,
            t_adapt * 1e3,
            t_reg * 1e3
        );
        print_row(n, t_step, t_solve, t_manage);
        // five runs, each followed by the solve alone on its last mesh, so that
        // each ratio compares times taken within a second of each other (this VM
        // drifts by up to 1.5× between minutes); the run with the median ratio
        let mut runs: Vec<(f64, f64, f64)> = (0..5)
            .map(|_| {
                let (t_run_manage, t_run_step, end) = curve_flow_run(&mesh, 40);
                let (_, t_run_solve) = l2_step_time(&end);
                (t_run_manage / t_run_solve, t_run_manage, t_run_step)
            })
            .collect();
        runs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (ratio, t_run_manage, t_run_step) = runs[2];
        eprintln!(
            "n={n}, curvature-flow run, mean of 40 steps (median of 5 runs): whole step {:.3} ms, management {:.3} ms, \
             solve alone (last mesh) {:.3} ms, management / solve {ratio:.2} (all five: {:.2?})",
            t_run_step * 1e3,
            t_run_manage * 1e3,
            t_run_manage / ratio * 1e3,
            runs.iter().map(|r| r.0).collect::<Vec<_>>()
        );
    }
    if std::env::var("CURVES_ONLY").is_ok() {
        return;
    }
    println!();
    println!("| surface vertices | L2 step (ms) | of which solve (ms) | management (ms) | management / step | management / solve |");
    println!("|---:|---:|---:|---:|---:|---:|");
    let mesh = icosphere([0.0; 3], 1.0, 6).unwrap();
    let n = mesh.num_vertices();
    let (t_step, t_solve) = l2_step_time(&mesh);
    let (params, pinch) = SurfaceManager::defaults_for(&mesh);
    let mut manager = SurfaceManager {
        regularize: true,
        sweeps: 3,
        adapt: true,
        params,
        pinch_curvature: Some(pinch),
        surgery: None,
        declined: None,
    };
    let mut managed_search = shapeflow::geometry::PatchSearch::default(); // the driver's, kept
    let t_manage = time_it(0.5, || {
        managed_search.forget(); // the driver manages each state once
        black_box(manager.manage_searched(&mesh, &mut managed_search).unwrap());
    });
    let t_stats = time_it(0.5, || _ = black_box(shapeflow::geometry::edge_statistics(&mesh)));
    let t_adapt = time_it(0.5, || _ = black_box(shapeflow::geometry::adapt_surface(&mesh, &params)));
    let t_reg = time_it(0.5, || _ = black_box(shapeflow::geometry::regularize_surface(&mesh, 3)));
    eprintln!(
        "n={n}: pinch check {:.1} ms, adapt {:.1} ms, regularize (3 sweeps) {:.1} ms",
        t_stats * 1e3,
        t_adapt * 1e3,
        t_reg * 1e3
    );
    print_row(n, t_step, t_solve, t_manage);

    // the intersection check of every trial step (3D), beside the L2 step: the
    // exhaustive search of the new state, and the watch (continuous along the
    // step, most pairs proved apart by its certificate) over the accepted steps of
    // a curvature flow of an ellipsoid, at a short and at a long step
    let (x, t) = (mesh.positions().to_vec(), mesh.elements().to_vec());
    let t_check = time_it(0.5, || {
        black_box(shapeflow::geometry::surface_intersections(&x, &t, 1));
    });
    // the patch search (the driver's), its patches cut once for the connectivity
    let mut search = shapeflow::geometry::PatchSearch::default();
    let t_patches = time_it(0.5, || {
        search.forget(); // searched each time, not answered from the last search
        black_box(search.intersections(&x, &t, 1));
    });
    // a new connectivity: the patches cut, then searched
    let t_cut = time_it(0.5, || {
        black_box(shapeflow::geometry::PatchSearch::default().intersections(&x, &t, 1));
    });
    let states = ellipsoid_states(1e-3, 40);
    let t_flow = (0..3) // the best of three passes
        .map(|_| {
            let start = Instant::now();
            states.iter().for_each(|state| assert!(search.intersections(state, &t, 1).is_empty()));
            start.elapsed().as_secs_f64() / states.len() as f64
        })
        .fold(f64::INFINITY, f64::min);
    let counts = |s: &shapeflow::geometry::PatchSearch| (s.embedded, s.groups + s.sealed, s.neighbours, s.tested);
    let flow_counts = counts(&search);
    let start = Instant::now();
    for state in &states {
        assert!(shapeflow::geometry::surface_intersections(state, &t, 1).is_empty());
    }
    let t_flow_exhaustive = start.elapsed().as_secs_f64() / states.len() as f64;
    search.forget();
    search.intersections(&x, &t, 1);
    println!();
    println!(
        "| surface vertices | L2 step (ms) | exhaustive search (ms) | search / step | patch search (ms) | \
         patch search / step | patches embedded | groups and seams proved embedded | patch pairs searched | pairs tested |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let row = |what: String, e: f64, p: f64, counts: String| {
        let step = t_step * 1e3;
        println!(
            "| {what} | {step:.1} | {:.1} | {:.2} | {:.2} | {:.3} | {counts} |",
            e * 1e3,
            e / t_step,
            p * 1e3,
            p / t_step
        );
    };
    let of = |(embedded, sealed, neighbours, tested): (usize, usize, usize, usize)| {
        format!("{embedded} of {} | {sealed} | {neighbours} | {tested}", search.patches_searched)
    };
    row(format!("sphere, {n}"), t_check, t_patches, of(counts(&search)));
    row(format!("sphere, {n}, patches cut anew (a new connectivity)"), t_check, t_cut, " | | | ".into());
    let flow = format!("ellipsoid flow, {n}, mean of {} states (best of three passes)", states.len());
    row(flow, t_flow_exhaustive, t_flow, of(flow_counts));
    // with merges (surgery), each trial's contact of the curved sheets too
    let t_gap = time_it(0.5, || _ = black_box(shapeflow::geometry::curved_sheet_gap(&x, &t)));
    let gap_flow =
        states.iter().map(|state| time_it(0.1, || _ = black_box(shapeflow::geometry::curved_sheet_gap(state, &t))));
    let t_gap_flow = gap_flow.sum::<f64>() / states.len() as f64;
    // two spheres whose facing sheets are close: the patches there are measured
    let facing = shapeflow::geometry::surface_union(&[
        shapeflow::geometry::icosphere([-1.0005, 0.0, 0.0], 1.0, 5).unwrap(),
        shapeflow::geometry::icosphere([1.0005, 0.0, 0.0], 1.0, 5).unwrap(),
    ])
    .unwrap();
    let t_gap_facing =
        time_it(0.5, || _ = black_box(shapeflow::geometry::curved_sheet_gap(facing.positions(), facing.elements())));
    println!();
    println!("| merging flows, {n} vertices | curved sheets' gap (ms) | gap / step |");
    println!("|---|---:|---:|");
    println!("| sphere | {:.1} | {:.2} |", t_gap * 1e3, t_gap / t_step);
    println!(
        "| ellipsoid flow, mean of {} states | {:.1} | {:.2} |",
        states.len(),
        t_gap_flow * 1e3,
        t_gap_flow / t_step
    );
    println!(
        "| two spheres of {} vertices together, 0.001 apart | {:.1} | {:.2} |",
        facing.num_vertices(),
        t_gap_facing * 1e3,
        t_gap_facing / t_step
    );
    println!();
    println!(
        "| ellipsoid flow, {n} vertices | most motion / edge | watch (ms) | watch / step | certificates drawn | \
         re-anchored | steps swept | pairs tested / step |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    for tau in [1e-4, 1e-3] {
        let states = ellipsoid_states(tau, 40);
        let mut best = f64::INFINITY;
        let mut watch = shapeflow::geometry::SurfaceWatch::default();
        for _ in 0..3 {
            watch = shapeflow::geometry::SurfaceWatch::default();
            let start = Instant::now();
            for w in states.windows(2) {
                assert!(watch.meetings(&w[0], &w[1], &t, 1).is_empty());
            }
            best = best.min(start.elapsed().as_secs_f64() / (states.len() - 1) as f64);
        }
        let edge = shapeflow::geometry::edge_statistics(&mesh).0;
        let most = states
            .windows(2)
            .map(|w| w[0].iter().zip(&w[1]).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        println!(
            "| τ = {tau:e}, {} steps | {:.2} | {:.2} | {:.2} | {} | {} | {} | {:.0} |",
            states.len() - 1,
            most / edge,
            best * 1e3,
            best / t_step,
            watch.drawn,
            watch.reanchored,
            watch.swept,
            watch.tested as f64 / (states.len() - 1) as f64
        );
    }
    surgery::table();
}
