//! The epitaxially stressed film (paper §4.4.2): the periodic surface-diffusion
//! limit, conservation and energy decay with the bulk field, and the inclusion.

use shapeflow::bulk::MeshingOptions;
use shapeflow::film::{cosine_film, BoundaryData, FilmCell};
use shapeflow::flow::{CurveManager, Flow, FlowSettings, MeshManager, ScalarProduct};
use shapeflow::geometry::{CurveMesh, Point};
use shapeflow::problems::StressedFilm;
use std::f64::consts::TAU;

/// `(2/L) ∫ (h − mean) cos(kx) dx` along the film surface (a graph), by the
/// trapezoidal rule on the lifted segments.
fn cosine_amplitude(c: &CurveMesh, l: f64, mode: f64) -> f64 {
    let k = TAU * mode / l;
    let mut s = 0.0;
    for e in 0..c.num_elements() {
        let [a, b] = c.element_points(e);
        s += 0.5 * (b.x - a.x) * (a.y * (k * a.x).cos() + b.y * (k * b.x).cos());
    }
    2.0 * s / l
}

fn film(l: f64, g: BoundaryData, gamma: f64, h: f64) -> StressedFilm {
    StressedFilm::new(FilmCell { length: l, boundary: g }, gamma, StressedFilm::meshing_for(h), true, 1e-3 * h * h)
}

fn settings(tau: f64, end: f64) -> FlowSettings {
    FlowSettings {
        scalar_product: ScalarProduct::HMinus1,
        tau,
        end_time: Some(end),
        max_iterations: 1_000_000,
        tolerance: 0.0,
        backtracking: false,
        step_control: std::env::var("EPS").ok().and_then(|s| s.parse().ok()),
        conservation: std::env::var("CONS").ok().and_then(|s| s.parse().ok()),
        ..FlowSettings::default()
    }
}

#[test]
fn small_cosine_decays_at_the_linear_rate() {
    let (l, gamma) = (1.0, 1.0);
    let k = TAU / l;
    let rate = gamma * k.powi(4);
    let mesh = cosine_film(l, 0.5, 1e-3, 1, 64).unwrap();
    let problem = film(l, BoundaryData::constant(0.0), gamma, l / 64.0);
    let a0 = cosine_amplitude(&mesh, l, 1.0);
    let end = 1.0 / rate;
    let mut flow = Flow::new(&problem, mesh, settings(end / 200.0, end)).unwrap();
    while flow.step().unwrap().stop.is_none() {}
    let a1 = cosine_amplitude(flow.mesh(), l, 1.0);
    let measured = (a0 / a1).ln() / flow.time();
    assert!((measured / rate - 1.0).abs() < 0.05, "rate {measured} vs γk⁴ = {rate}");
}

#[test]
#[ignore]
fn explore() {
    let l = 1.0;
    let n = 128;
    let gamma: f64 = std::env::var("GAMMA").ok().and_then(|s| s.parse().ok()).unwrap_or(0.2);
    let height: f64 = std::env::var("HEIGHT").ok().and_then(|s| s.parse().ok()).unwrap_or(0.5);
    let amp: f64 = std::env::var("AMP").ok().and_then(|s| s.parse().ok()).unwrap_or(0.02);
    let tend: f64 = std::env::var("TEND").ok().and_then(|s| s.parse().ok()).unwrap_or(0.05);
    let tau: f64 = std::env::var("TAU").ok().and_then(|s| s.parse().ok()).unwrap_or(1e-5);
    let mesh = cosine_film(l, height, amp, 1, n).unwrap();
    let problem = film(l, BoundaryData::x(), gamma, l / n as f64);
    let mut m = CurveManager::defaults_for(&mesh);
    let mut cm = CurveManager { regularize: true, sweeps: 1, adapt: true, topology_changes: true, params: m };
    cm.params.h_min = 0.25 * l / n as f64;
    m = cm.params;
    let _ = m;
    let mut flow = Flow::new(&problem, mesh, settings(tau, tend))
        .unwrap()
        .with_mesh_manager(Box::new(cm) as Box<dyn MeshManager<2>>);
    let a0 = flow.mesh().enclosed_measure();
    let mut it = 0;
    let mut prev_area = a0;
    let mut prev_comps = 1;
    loop {
        let r = flow.step();
        match r {
            Err(e) => {
                println!("error {e}");
                break;
            }
            Ok(r) if r.stop.is_some() => {
                println!("stop {:?}", r.stop);
                break;
            }
            _ => {}
        }
        it += 1;
        let a = flow.mesh().enclosed_measure();
        if (a - prev_area).abs() > 1e-5 || flow.mesh().num_components() != prev_comps {
            let w = flow.mesh().windings();
            let areas: Vec<String> = flow
                .mesh()
                .lifted_cycles()
                .iter()
                .zip(&w)
                .map(|((p, s), w)| {
                    let n = p.len();
                    format!(
                        "w{w}:{:.5}/{}",
                        (0..n)
                            .map(|k| {
                                let b = if k + 1 < n { p[k + 1] } else { p[0] + s };
                                -0.5 * (b.x - p[k].x) * (p[k].y + b.y)
                            })
                            .sum::<f64>(),
                        n
                    )
                })
                .collect();
            println!(
                "  it {it} t {:.6} area {a:.6} (Δ {:.2e}) comps {:?} E {:.5}",
                flow.time(),
                a - prev_area,
                areas,
                flow.energy()
            );
        }
        prev_area = a;
        prev_comps = flow.mesh().num_components();
        if it % 200 == 0 {
            let mut out = String::new();
            for (pts, _) in flow.mesh().lifted_cycles() {
                for p in &pts {
                    out += &format!("{} {}\n", p.x, p.y);
                }
                out += "\n";
            }
            std::fs::write(format!("{}_{:06}.txt", std::env::var("OUT").unwrap_or("/tmp/film".into()), it), out)
                .unwrap();
            let c = flow.mesh();
            let ys: Vec<f64> = c.positions().iter().map(|p| p.y).collect();
            let (lo, hi) = (ys.iter().cloned().fold(f64::MAX, f64::min), ys.iter().cloned().fold(f64::MIN, f64::max));
            println!(
                "it {it} t {:.5} E {:.6} area {:.3e} comps {} nv {} y [{lo:.3}, {hi:.3}]",
                flow.time(),
                flow.energy(),
                flow.mesh().enclosed_measure() / a0 - 1.0,
                c.num_components(),
                c.num_vertices()
            );
        }
    }
    let c = flow.mesh();
    for (pts, _) in c.lifted_cycles() {
        let s: Vec<String> = pts.iter().step_by(4).map(|p| format!("({:.3},{:.3})", p.x, p.y)).collect();
        println!("{}", s.join(" "));
    }
    let _ = Point::<2>::zeros();
    let _ = MeshingOptions { min_angle_deg: 1.0, max_area: 1.0, min_area: 0.0 };
}

/// Growth rate of the linear instability with `g = x` (Laplace analogue of the
/// Asaro–Tiller–Grinfeld instability): for `h = H + δ cos kx`, `y = x + u` with
/// `u = −δ sin(kx) sinh(ky)/cosh(kH)` (which vanishes on the walls and the
/// substrate) gives `|∇y|² = 1 − 2δk tanh(kH) cos kx` on `Γ` to first order, and
/// `V = Δ_Γ(γκ + |∇y|²)` gives `σ = 2k³ tanh(kH) − γk⁴`.
fn growth_rate(gamma: f64, n: usize) -> (f64, f64) {
    let (l, height) = (1.0, 0.5);
    let k = TAU / l;
    let sigma = 2.0 * k.powi(3) * (k * height).tanh() - gamma * k.powi(4);
    let mesh = cosine_film(l, height, 1e-3, 1, n).unwrap();
    let problem = film(l, BoundaryData::x(), gamma, l / n as f64);
    let a0 = cosine_amplitude(&mesh, l, 1.0);
    let end = 1.0 / sigma.abs();
    let mut flow = Flow::new(&problem, mesh, settings(end / 400.0, end)).unwrap();
    while flow.step().unwrap().stop.is_none() {}
    let a1 = cosine_amplitude(flow.mesh(), l, 1.0);
    ((a1 / a0).ln() / flow.time(), sigma)
}

#[test]
fn the_linear_instability_grows_at_the_predicted_rate() {
    // γ = 0.2: mode 1 unstable (σ ≈ 182.5); γ = 0.5: stable (σ ≈ −285)
    for gamma in [0.2, 0.5] {
        let (measured, sigma) = growth_rate(gamma, 128);
        assert!((measured / sigma - 1.0).abs() < 0.05, "γ = {gamma}: rate {measured} vs σ = {sigma}");
    }
}
