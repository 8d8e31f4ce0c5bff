//! The paper's scenario: a groove closes off a void in finite time, at a time and
//! size stable under refinement, also with a bending energy.

use super::*;

/// The paper's scenario (examples/stressed_film.json) at `resolution` vertices, to
/// t = 0.0085.
fn paper_job(resolution: usize) -> PreparedJob {
    let spec = std::fs::read_to_string("examples/stressed_film.json")
        .unwrap()
        .replace("\"resolution\": 128", &format!("\"resolution\": {resolution}"))
        .replace("\"end_time\": 0.0067", "\"end_time\": 0.0085");
    job(&spec)
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
