//! The periodic surface-diffusion limit and the linear (Asaro–Tiller–Grinfeld)
//! stability of a small cosine.

use super::*;

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
        step_control: None,
        ..FlowSettings::default()
    }
}

#[test]
fn small_cosine_decays_at_the_linear_rate() {
    let (l, gamma) = (1.0, 1.0);
    let k = TAU / l;
    let rate = gamma * k.powi(4);
    let mesh = cosine_film(l, 0.5, 1e-3, 1, 64).unwrap();
    let mut problem = film(l, BoundaryData::constant(0.0), gamma, l / 64.0).start();
    let a0 = cosine_amplitude(&mesh, l, 1.0);
    let end = 1.0 / rate;
    let mut flow = Flow::new(&mut problem, mesh, settings(end / 200.0, end)).unwrap();
    while flow.step().unwrap().stop.is_none() {}
    let a1 = cosine_amplitude(flow.mesh(), l, 1.0);
    let measured = (a0 / a1).ln() / flow.time();
    assert!((measured / rate - 1.0).abs() < 0.05, "rate {measured} vs γk⁴ = {rate}");
}

/// With a bending energy `ε/2 ∫ κ²` (an addition) the chemical potential gains
/// `−εΔ_Γκ`: `h_t = −γh'''' + εh''''''`, so the cosine decays at `γk⁴ + εk⁶`. With
/// `ε = γ/k²` both terms are equal: the rate doubles.
#[test]
fn with_bending_a_small_cosine_decays_at_gamma_k4_plus_eps_k6() {
    let (l, gamma) = (1.0, 1.0);
    let k = TAU / l;
    let eps = gamma / (k * k);
    let rate = gamma * k.powi(4) + eps * k.powi(6);
    let mesh = cosine_film(l, 0.5, 1e-3, 1, 64).unwrap();
    let mut problem = film(l, BoundaryData::constant(0.0), gamma, l / 64.0).with_bending(eps).start();
    let a0 = cosine_amplitude(&mesh, l, 1.0);
    let end = 1.0 / rate;
    let mut flow = Flow::new(&mut problem, mesh, settings(end / 200.0, end)).unwrap();
    let e0 = flow.energy();
    while flow.step().unwrap().stop.is_none() {}
    let a1 = cosine_amplitude(flow.mesh(), l, 1.0);
    let measured = (a0 / a1).ln() / flow.time();
    assert!((measured / rate - 1.0).abs() < 0.05, "rate {measured} vs γk⁴ + εk⁶ = {rate}");
    // J = γ|Γ| + ε/2 ∫κ², both parts decreasing; the bending part of the start
    // value is ε/2 · (δk²)² · L/2 to leading order
    let bend0 = e0 - gamma * (1.0 + (1e-3 * k).powi(2) / 4.0);
    let expected = 0.5 * eps * (1e-3 * k * k).powi(2) * 0.5;
    assert!((bend0 / expected - 1.0).abs() < 0.05, "bending energy {bend0} vs {expected}");
    assert!(flow.energy() < e0);
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
    let mut problem = film(l, BoundaryData::x(), gamma, l / n as f64).start();
    let a0 = cosine_amplitude(&mesh, l, 1.0);
    let end = 1.0 / sigma.abs();
    let mut flow = Flow::new(&mut problem, mesh, settings(end / 400.0, end)).unwrap();
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
