use shapeflow::flow::{CurveManager, Flow, FlowSettings};
use shapeflow::geometry::{polygon, Point};
use shapeflow::problems::CurvatureFlow;

fn main() {
    shapeflow::tune_allocator();
    let n = 10_000;
    let pts: Vec<Point<2>> = (0..n)
        .map(|k| {
            let u = k as f64 / n as f64;
            let t = 2.0 * std::f64::consts::PI * (u + 0.05 * (2.0 * std::f64::consts::PI * u).sin() / 6.3);
            let r = 1.0 + 0.05 * (7.0 * t).cos();
            Point::<2>::new(r * t.cos(), r * t.sin())
        })
        .collect();
    let mesh0 = polygon(&pts, None).unwrap();
    let params = CurveManager::defaults_for(&mesh0);
    println!("{params:?}");
    let problem = CurvatureFlow { gamma: 1.0, lambda: 0.0 };
    let settings = FlowSettings { tau: 1e-4, tolerance: 0.0, ..FlowSettings::default() };
    let manager = CurveManager { regularize: true, sweeps: 1, adapt: true, topology_changes: true, params };
    let mut flow = Flow::new(&problem, mesh0.clone(), settings).unwrap().with_mesh_manager(Box::new(manager.watched()));
    for k in 0..400 {
        flow.step().unwrap();
        let m = flow.mesh();
        if k % 100 != 0 {
            continue;
        }
        let q = m.quality();
        let x = m.positions();
        let lens: Vec<f64> = m.elements().iter().map(|e| (x[e[1]] - x[e[0]]).norm()).collect();
        let over = lens.iter().filter(|&&l| l > 0.8 * params.h_max).count();
        if k % 100 == 0 {
            println!(
                "step {k}: n {} min {:.3e} max {:.3e} over0.8hmax {over}",
                m.num_vertices(),
                q.min_edge,
                q.max_edge
            );
        }
    }
}
