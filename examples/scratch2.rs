use shapeflow::flow::*;
use shapeflow::geometry::*;
use shapeflow::problems::*;
fn main() {
    let a: Vec<f64> = std::env::args().skip(1).map(|s| s.parse().unwrap()).collect();
    let problem = CurvatureFlow { gamma: 1.0, lambda: a[0] };
    let settings = FlowSettings { tau: a[1], max_iterations: a[2] as usize, tolerance: 0.0, step_control: if a[4] > 0.0 { Some(a[4]) } else { None }, ..FlowSettings::default() };
    let n = 128;
    let pts: Vec<Point<2>> = (0..n).map(|k| { let t = 2.0*std::f64::consts::PI*k as f64/n as f64; let r = 1.0 + a[3]*(5.0*t).cos(); Point::<2>::new(r*t.cos(), r*t.sin()) }).collect();
    let mut flow = Flow::new(&problem, polygon(&pts, None).unwrap(), settings).unwrap();
    for _ in 0..1000 {
        let r = flow.step();
        match r { Ok(r) => { let p = flow.progress(); println!("bt {} red {} it {} t {:.4} tau {:.3e} J {:.5}", r.backtracks, r.reductions, p.iteration, p.time, p.tau, p.energy); if r.stop.is_some() { break; } }
        Err(e) => { println!("{e}"); break; } }
    }
}
