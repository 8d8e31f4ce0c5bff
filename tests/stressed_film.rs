//! The epitaxially stressed film (paper §4.4.2): the periodic surface-diffusion
//! limit, conservation and energy decay with the bulk field, and the inclusion.

use shapeflow::export::shape_json;
use shapeflow::film::{cosine_film, BoundaryData, FilmCell};
use shapeflow::flow::{Flow, FlowSettings, MeshData, MeshManager, Problem, ScalarProduct};
use shapeflow::geometry::CurveMesh;
use shapeflow::jobs::{parse_spec, prepare, AnyMesh, PreparedJob, ProblemKind};
use shapeflow::problems::StressedFilm;
use std::collections::HashMap;
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
    let problem = film(l, BoundaryData::constant(0.0), gamma, l / 64.0);
    let a0 = cosine_amplitude(&mesh, l, 1.0);
    let end = 1.0 / rate;
    let mut flow = Flow::new(&problem, mesh, settings(end / 200.0, end)).unwrap();
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
    let problem = film(l, BoundaryData::constant(0.0), gamma, l / 64.0).with_bending(eps);
    let a0 = cosine_amplitude(&mesh, l, 1.0);
    let end = 1.0 / rate;
    let mut flow = Flow::new(&problem, mesh, settings(end / 200.0, end)).unwrap();
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

fn job(spec: &str) -> PreparedJob {
    prepare(parse_spec(spec).unwrap(), &HashMap::new()).unwrap()
}

/// Areas of the closed components (voids) of a periodic curve.
fn void_areas(c: &CurveMesh) -> Vec<f64> {
    c.lifted_cycles()
        .iter()
        .zip(c.windings())
        .filter(|(_, w)| *w == 0)
        .map(|((p, _), _)| {
            (0..p.len()).map(|k| 0.5 * (p[k].x * p[(k + 1) % p.len()].y - p[(k + 1) % p.len()].x * p[k].y)).sum()
        })
        .collect()
}

/// The paper's scenario (examples/stressed_film.json) at `resolution` vertices, to
/// t = 0.0085.
fn paper_job(resolution: usize) -> PreparedJob {
    let spec = std::fs::read_to_string("examples/stressed_film.json")
        .unwrap()
        .replace("\"resolution\": 128", &format!("\"resolution\": {resolution}"))
        .replace("\"end_time\": 0.0067", "\"end_time\": 0.0085");
    job(&spec)
}

/// The flow of a film job with its mesh manager.
fn managed_flow(job: &PreparedJob) -> Flow<'_, 2> {
    let (ProblemKind::StressedFilm(problem), AnyMesh::Curve(mesh)) = (&job.problem, &job.mesh) else { unreachable!() };
    Flow::new(problem as &dyn Problem<2>, mesh.clone(), job.settings.clone())
        .unwrap()
        .with_mesh_manager(Box::new(job.curve_manager.unwrap()) as Box<dyn MeshManager<2>>)
}

/// The paper's scenario (examples/stressed_film.json at 64 vertices): the film
/// keeps its area and J decreases while it is a graph and then a groove; a void
/// closes off in finite time and keeps its area; the run goes on through further
/// reconnections.
#[test]
fn the_groove_closes_off_a_void_in_finite_time() {
    let job = paper_job(64);
    let mut flow = managed_flow(&job);
    let area0 = flow.mesh().enclosed_measure();
    let mut energy = flow.energy();
    let energy0 = energy;
    let mut rises = Vec::new();
    let mut formed = None;
    while formed.is_none() {
        let r = flow.step().unwrap();
        assert!(r.stop.is_none(), "no void by t = {}", flow.time());
        let drift = (flow.mesh().enclosed_measure() / area0 - 1.0).abs();
        if !void_areas(flow.mesh()).is_empty() {
            formed = Some((flow.time(), void_areas(flow.mesh())[0], drift));
            break;
        }
        // non-increasing while the trough deepens, up to the discretization error of
        // the bulk (re-triangulated every step); once it is a crack whose tip pinches
        // off slivers below `min_area`, J also jumps at those topological events
        let bottom = flow.mesh().positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        let rise = flow.energy() / energy - 1.0;
        if bottom > 0.25 && rise > 0.0 {
            rises.push((flow.time(), rise));
        }
        // each step's O(τ²) change is removed (measured: 6e-7 at the void)
        assert!(drift < 1e-5, "area drift {drift:e} at t = {}", flow.time());
        energy = flow.energy();
    }
    let (t, area, drift) = formed.unwrap();
    println!("void at t = {t}: area {area:e}, film area drift {drift:e}, J {energy0} → {energy}, rises {rises:?}");
    assert!(energy < 0.98 * energy0, "J {energy0} → {energy}");
    // measured: J strictly decreases until the last 0.5 % of the time before the
    // void, then rises twice by ≤ 7e-5 (relative) as the crack runs
    for &(at, rise) in &rises {
        assert!(at > 0.99 * t && rise < 1e-4, "J rose by {rise:e} at t = {at} (void at {t})");
    }
    assert!(t > 0.006 && t < 0.008, "void at t = {t}");
    assert!(area > 1e-4, "void area {area}");
    // the void is a counter-clockwise closed component; shape.json lists it
    let doc = shape_json(&MeshData::from(flow.mesh()), flow.energy(), flow.iteration(), None);
    assert_eq!(doc["period"], 1.0);
    let windings: Vec<u64> =
        doc["components"].as_array().unwrap().iter().map(|c| c["winding"].as_u64().unwrap()).collect();
    assert!(windings.contains(&0) && windings.contains(&1), "{windings:?}");
    // the run goes on: the crack above the void heals back (its tip retracts into a
    // bulb), runs down again, reopens the void into the surface and closes it off
    // anew, larger (measured at 64 vertices: the first void lives 1.3e-5, the second
    // closes off 2.5e-5 after the first). Each void keeps its area while it is
    // closed, and the film keeps its area throughout.
    let film0 = flow.mesh().enclosed_measure();
    let (mut births, mut current, mut first_life) = (vec![(t, area)], Some((t, area)), None);
    while flow.time() < t + AFTER {
        let r = flow.step().unwrap();
        assert!(r.stop.is_none(), "stopped {:?} at t = {} after the void", r.stop, flow.time());
        let drift = (flow.mesh().enclosed_measure() / film0 - 1.0).abs();
        assert!(drift < 1e-3, "film area drift {drift:e} at t = {}", flow.time());
        let v = void_areas(flow.mesh());
        match (v.len(), current) {
            (1, Some((_, a))) => {
                assert!((v[0] / a - 1.0).abs() < VOID_TOL, "void area {a} → {} at t = {}", v[0], flow.time())
            }
            (1, None) => {
                current = Some((flow.time(), v[0]));
                births.push((flow.time(), v[0]));
            }
            (0, Some((born, _))) => {
                first_life.get_or_insert(flow.time() - born);
                current = None;
            }
            (0, None) => {}
            (n, _) => panic!("{n} voids at t = {}", flow.time()),
        }
    }
    println!("voids closed off (time, area): {births:?}; the first lived {first_life:?}");
    assert!(first_life.is_none_or(|l| l > 5e-6), "the first void lived {first_life:?}");
    assert!(births.len() >= 2, "one void only: {births:?}");
}

/// The paper's scenario at `resolution` vertices, run until the first void closes
/// off: its time, and the change of J in the step that closed it off.
fn first_void(resolution: usize) -> (f64, f64) {
    let job = paper_job(resolution);
    let mut flow = managed_flow(&job);
    let mut before = flow.energy();
    while void_areas(flow.mesh()).is_empty() {
        before = flow.energy();
        let r = flow.step().unwrap();
        assert!(r.stop.is_none(), "no void by t = {} at {resolution} vertices", flow.time());
    }
    (flow.time(), flow.energy() - before)
}

/// Refinement study (issue: the time at which the inclusion forms is stable to 5 %
/// when the mesh is refined): the first void at 64, 96 and 128 vertices, measured
/// t = 0.00700, 0.00677, 0.00667. Each refinement changes it by less than 5 %, and
/// the change shrinks (3.4 %, then 1.5 %). The rise of J at that reconnection (the
/// walls welded over the void can carry the field across, which raises the
/// Dirichlet energy) is a discretization effect that shrinks under refinement:
/// measured 0.073, 0.060, 0.047 (0.039 at 192 vertices).
#[test]
fn the_void_forms_at_a_time_stable_under_refinement() {
    let runs: Vec<(f64, f64)> = std::thread::scope(|s| {
        let runs: Vec<_> = [64, 96, 128].map(|n| s.spawn(move || first_void(n))).into_iter().collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    let t: Vec<f64> = runs.iter().map(|r| r.0).collect();
    let jumps: Vec<f64> = runs.iter().map(|r| r.1).collect();
    let change = |a: f64, b: f64| (a / b - 1.0).abs();
    let (coarse, fine) = (change(t[0], t[1]), change(t[1], t[2]));
    println!("first void at t = {t:?}: changes {coarse:.4}, {fine:.4}; J jumps {jumps:?}");
    assert!(coarse < 0.05 && fine < 0.05, "{t:?}");
    assert!(fine < coarse, "not converging: {t:?}");
    assert!(t.iter().all(|&x| x > 0.0064 && x < 0.0072), "{t:?}");
    assert!(jumps[0] < 0.1 && jumps[1] < 0.9 * jumps[0] && jumps[2] < 0.9 * jumps[1], "J jumps {jumps:?}");
}

/// The paper's scenario with a bending energy `ε/2 ∫ κ²`, `ε = 2·10⁻⁴`
/// (`examples/stressed_film_bending.json`, an addition) at `resolution` vertices, run
/// until the first inclusion closes off (the film's area kept to 1e-3 and J
/// decreasing at every step on the way): its time, area and height; then up to 100
/// steps more while it stays closed, keeping its area to 1 %.
fn first_inclusion_with_bending(resolution: usize) -> (f64, f64, f64) {
    let spec = std::fs::read_to_string("examples/stressed_film_bending.json")
        .unwrap()
        .replace("\"resolution\": 128", &format!("\"resolution\": {resolution}"));
    let job = job(&spec);
    let mut flow = managed_flow(&job);
    let film0 = flow.mesh().enclosed_measure();
    let mut energy = flow.energy();
    let (time, area, height) = loop {
        let r = flow.step().unwrap();
        assert!(r.stop.is_none(), "no inclusion by t = {} at {resolution} vertices", flow.time());
        let c = flow.mesh();
        let drift = (c.enclosed_measure() / film0 - 1.0).abs();
        assert!(drift < 1e-3, "{resolution} vertices: film area drift {drift:e} at t = {}", flow.time());
        if let Some((area, ((p, _), _))) = void_areas(c)
            .into_iter()
            .zip(c.lifted_cycles().into_iter().zip(c.windings()).filter(|(_, w)| *w == 0))
            .next()
        {
            let (lo, hi) = p.iter().fold((f64::MAX, f64::MIN), |(lo, hi), q| (lo.min(q.y), hi.max(q.y)));
            break (flow.time(), area, hi - lo);
        }
        // J decreases at every step while the surface is one curve (measured)
        assert!(flow.energy() <= energy, "{resolution} vertices: J rose to {} at t = {}", flow.energy(), flow.time());
        energy = flow.energy();
    };
    // the inclusion keeps its area while it stays closed (it reopens later). Its
    // sharp top can pinch off a sliver below `mesh.min_area`, which is dropped:
    // measured at 128 vertices 1.0e-4 (1.8 %) three steps after it closed off, and
    // no change above 1e-7 otherwise.
    let mut last = area;
    for _ in 0..100 {
        flow.step().unwrap();
        match void_areas(flow.mesh())[..] {
            [a] => {
                assert!((a / area - 1.0).abs() < 0.025, "{resolution} vertices: inclusion {area} → {a}");
                last = a;
            }
            _ => break,
        }
    }
    println!("{resolution} vertices: inclusion area {area} at t = {time}, {last} 100 steps later or at reopening");
    (time, area, height)
}

/// With the bending energy the crack tip has a radius of about `√(ε/γ)` instead of
/// a segment, and the groove becomes a keyhole (a neck over a round bulb, the film
/// above it overhanging) whose neck closes off a teardrop inclusion. Unlike the
/// void of the plain model (areas 9.7e-4, 5.7e-4, 3.8e-4 at 64, 96, 128 vertices,
/// one segment wide), both its time and its size converge under refinement.
/// Measured at 64, 96, 128 vertices: t = 0.010030, 0.009781, 0.009682 (changes
/// 2.5 %, 1.0 %), area 6.76e-3, 5.80e-3, 5.41e-3 (14 %, 6.9 %), height 0.183,
/// 0.170, 0.170.
#[test]
fn with_bending_the_inclusion_forms_at_a_converged_time_and_size() {
    let runs: Vec<(f64, f64, f64)> = std::thread::scope(|s| {
        let runs: Vec<_> =
            [64, 96, 128].map(|n| s.spawn(move || first_inclusion_with_bending(n))).into_iter().collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    println!("first inclusion (time, area, height): {runs:?}");
    let change = |a: f64, b: f64| (a / b - 1.0).abs();
    let (t, a): (Vec<f64>, Vec<f64>) = runs.iter().map(|r| (r.0, r.1)).unzip();
    assert!(change(t[0], t[1]) < 0.05 && change(t[1], t[2]) < 0.05, "times {t:?}");
    assert!(change(t[1], t[2]) < change(t[0], t[1]), "times not converging: {t:?}");
    assert!(t.iter().all(|&x| x > 0.0093 && x < 0.0105), "times {t:?}");
    // the area converges (the plain model's shrinks by 40 % per refinement)
    assert!(change(a[0], a[1]) < 0.2 && change(a[1], a[2]) < 0.1, "areas {a:?}");
    assert!(change(a[1], a[2]) < change(a[0], a[1]), "areas not converging: {a:?}");
    // a finite inclusion: mean width above 0.025, three segments at 128 vertices
    // (the plain model's void at 128 vertices: 0.0053, 0.7 of a segment)
    for (n, (_, area, height)) in [64, 96, 128].iter().zip(&runs) {
        assert!(*area > 4e-3 && area / height > 0.025, "{n} vertices: area {area}, height {height}");
    }
}

/// How long the test runs on after the first void closes off.
const AFTER: f64 = 4e-5;
/// Relative change of a void's area allowed while it stays closed.
const VOID_TOL: f64 = 0.01;

#[test]
fn spec_errors_name_the_field() {
    let base = r#"{"problem": {"type": "stressed_film", "length": 1.0, "gamma": 0.2},
                   "initial": {"shape": "film", "height": 0.5, "amplitude": 0.02}}"#;
    let err = |text: &str| -> String {
        match parse_spec(text) {
            Err(e) => e.field,
            Ok(spec) => prepare(spec, &HashMap::new()).unwrap_err().field,
        }
    };
    assert!(prepare(parse_spec(base).unwrap(), &HashMap::new()).is_ok());
    assert_eq!(err(&base.replace("\"length\": 1.0", "\"length\": -1.0")), "problem.length");
    assert_eq!(err(&base.replace("\"gamma\": 0.2", "\"gamma\": 0")), "problem.gamma");
    assert_eq!(
        err(&base.replace("\"gamma\": 0.2", "\"gamma\": 0.2, \"boundary\": {\"type\": \"y\"}")),
        "problem.boundary.type"
    );
    assert_eq!(err(&base.replace("\"length\": 1.0, ", "")), "problem.length");
    assert_eq!(err(&base.replace("\"amplitude\": 0.02", "\"amplitude\": 0.7")), "initial.amplitude");
    let wet = |d: &str| base.replace("\"gamma\": 0.2", &format!("\"gamma\": 0.2, \"wetting_layer\": {d}"));
    assert!(prepare(parse_spec(&wet("0.02")).unwrap(), &HashMap::new()).is_ok());
    assert_eq!(err(&wet("-0.1")), "problem.wetting_layer");
    assert_eq!(err(&wet("0.49")), "problem.wetting_layer");
    let bend = |e: &str| base.replace("\"gamma\": 0.2", &format!("\"gamma\": 0.2, \"bending\": {e}"));
    assert!(prepare(parse_spec(&bend("2e-4")).unwrap(), &HashMap::new()).is_ok());
    assert_eq!(err(&bend("-1e-4")), "problem.bending");
    let with_flow =
        |flow: &str| bend("2e-4").replace("\"amplitude\": 0.02}", &format!("\"amplitude\": 0.02}}, \"flow\": {flow}"));
    assert_eq!(err(&with_flow(r#"{"scalar_product": "l2"}"#)), "problem.bending");
    assert_eq!(err(&with_flow(r#"{"solver": "consistent"}"#)), "problem.bending");
    assert!(prepare(
        parse_spec(&with_flow(r#"{"solver": "consistent"}"#).replace("2e-4", "0")).unwrap(),
        &HashMap::new()
    )
    .is_ok());
    assert_eq!(
        err(&base.replace(
            "\"shape\": \"film\", \"height\": 0.5, \"amplitude\": 0.02",
            "\"shape\": \"circle\", \"radius\": 1"
        )),
        "initial.shape"
    );
    let poly = base.replace(
        "\"shape\": \"film\", \"height\": 0.5, \"amplitude\": 0.02",
        "\"shape\": \"film_polyline\", \"points\": [[0, 0.5], [0.5, 0.6], [1.2, 0.5]]",
    );
    assert_eq!(err(&poly), "initial.points[2]");
    let flat = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "film", "height": 0.5}}"#;
    assert_eq!(err(flat), "initial.shape");
}

/// Width of the gas at height `y` over one period: the film surface (the component
/// that winds around the cylinder, gas on its left as it runs in `+x`) crosses the
/// line `y`; the gas lies right of each downward crossing up to the next crossing.
fn gas_width(c: &CurveMesh, y: f64) -> f64 {
    let l = c.period().unwrap();
    let (surface, shift) =
        c.lifted_cycles().into_iter().zip(c.windings()).find(|(_, w)| *w != 0).map(|(p, _)| p).unwrap();
    let n = surface.len();
    let mut hits: Vec<(f64, bool)> = Vec::new();
    for k in 0..n {
        let (a, b) = (surface[k], if k + 1 == n { surface[0] + shift } else { surface[k + 1] });
        if (a.y - y) * (b.y - y) < 0.0 {
            let x = a.x + (y - a.y) / (b.y - a.y) * (b.x - a.x);
            hits.push((x.rem_euclid(l), b.y < a.y));
        }
    }
    hits.sort_by(|p, q| p.0.total_cmp(&q.0));
    (0..hits.len())
        .filter(|&i| hits[i].1)
        .map(|i| if i + 1 < hits.len() { hits[i + 1].0 - hits[i].0 } else { hits[0].0 + l - hits[i].0 })
        .sum()
}

/// How much wider the gas is somewhere below a height than at it: `max w(y₁) − w(y₂)`
/// over `y₁ < y₂` (0 for a graph). Positive: the film overhangs the gas (its caps
/// reach over a wider foot), a mushroom.
fn undercut(c: &CurveMesh) -> f64 {
    let ys: Vec<f64> = c.positions().iter().map(|p| p.y).collect();
    let (lo, hi) = (ys.iter().copied().fold(f64::INFINITY, f64::min), ys.iter().copied().fold(0.0, f64::max));
    let mut narrowest_above = f64::INFINITY;
    let mut best = 0.0f64;
    for k in (0..400).rev() {
        let w = gas_width(c, lo + (hi - lo) * (k as f64 + 0.5) / 400.0);
        narrowest_above = narrowest_above.min(w);
        best = best.max(w - narrowest_above);
    }
    best
}

/// With a wetting layer (`problem.wetting_layer`, an addition) the groove that
/// reaches the substrate spreads along the layer instead of ending the run: a thin
/// film (H = 0.4, γ = 0.15, 64 vertices) stands on it as a mushroom whose caps
/// overhang the channel. Measured: the crack reaches the layer at t = 0.0034; at
/// t = 0.012 the gas at the foot is 0.121 wider than at the neck.
#[test]
fn with_a_wetting_layer_the_film_stands_on_it_as_a_mushroom() {
    let spec = r#"{"problem": {"type": "stressed_film", "length": 1.0, "gamma": 0.15, "wetting_layer": 0.02},
        "initial": {"shape": "film", "height": 0.4, "amplitude": 0.02, "mode": 1, "resolution": 64},
        "flow": {"tau": 1e-5, "end_time": 0.012, "max_iterations": 1000000, "tolerance": 0}}"#;
    let job = job(spec);
    let mut flow = managed_flow(&job);
    let area0 = flow.mesh().enclosed_measure();
    let (mut lowest, mut on_layer, mut drift) = (f64::INFINITY, None, 0.0f64);
    loop {
        let r = flow.step().unwrap();
        if r.stop == Some(shapeflow::flow::StopReason::EndTime) {
            break;
        }
        assert!(r.stop.is_none(), "stopped {:?} at t = {}", r.stop, flow.time());
        let low = flow.mesh().positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        lowest = lowest.min(low);
        if low < 0.0201 && on_layer.is_none() {
            on_layer = Some(flow.time());
        }
        drift = drift.max((flow.mesh().enclosed_measure() / area0 - 1.0).abs());
    }
    let u = undercut(flow.mesh());
    println!(
        "on the layer from t = {on_layer:?}; lowest vertex {lowest}; largest area drift {drift:e}; undercut at t = {}: {u}",
        flow.time()
    );
    // the per-step correction keeps the area; what is left comes from the slivers
    // that reconnections at the crack tip drop (measured 1.3e-3), and the correction
    // offsets the surface on the layer by ~1e-4 (measured lowest 0.01986)
    assert!(drift < 2e-3, "film area drift {drift:e}");
    assert!(lowest > 0.0198, "below the wetting layer: {lowest}");
    assert!(on_layer.is_some_and(|t| t < 0.008), "the groove never reached the layer: {on_layer:?}");
    assert!(void_areas(flow.mesh()).is_empty(), "the channel closed");
    assert!(u > 0.08, "no overhang: {u}");
}
