use shapeflow::flow::*;
use shapeflow::geometry::*;
use shapeflow::problems::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let level: u32 = args[1].parse().unwrap();
    let tau: f64 = args[2].parse().unwrap();
    let end: f64 = args[3].parse().unwrap();
    let mesh = ellipsoid([0.0; 3], [1.0, 0.5, 0.5], level).unwrap();
    let r_eq = (3.0 * mesh.enclosed_measure() / (4.0 * std::f64::consts::PI)).cbrt();
    let problem = SurfaceDiffusion { gamma: 1.0 };
    let settings = FlowSettings { scalar_product: ScalarProduct::HMinus1, tau, max_iterations: usize::MAX, end_time: Some(end), tolerance: 0.0, backtracking: false, step_control: args.get(4).map(|s| s.parse().unwrap()), ..Default::default() };
    let vol0 = mesh.enclosed_measure(); let mut flow = Flow::new(&problem, mesh, settings).unwrap();
    let t0 = std::time::Instant::now();
    flow.run(&std::sync::atomic::AtomicBool::new(false), |f| {
        if f.iteration() % 100 == 0 || f.time() >= end - 1e-12 {
            let m = f.mesh(); let c = m.vertex_centroid();
            let dev = m.positions().iter().map(|p| ((p - c).norm() - r_eq).abs()).fold(0.0, f64::max) / r_eq;
            println!("it {} t {:.4} tau {:.2e} dev {:.3e} area {:.8} vol drift {:.2e}", f.iteration(), f.time(), f.progress().tau, dev, m.boundary_measure(), m.enclosed_measure()/vol0-1.0);
        }
    }).unwrap();
    println!("{:?}", t0.elapsed());
}
