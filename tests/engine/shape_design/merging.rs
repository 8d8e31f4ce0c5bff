//! Curves that meet merge: two squares into one curve, curves driven into
//! contact, the square ring into one smoothed square.

use super::*;

/// Every progress report of a run (energy and number of components).
struct Trace(Vec<shapeflow::flow::Progress>);
impl RunEvents for Trace {
    fn progress(&mut self, p: &shapeflow::flow::Progress) {
        self.0.push(*p);
    }
}

/// Two squares of side `side` centred at `(±center, 0)` on the ring of Test 1.
fn squares(side: f64, center: f64, iterations: usize) -> String {
    format!(
        r#"{{"problem": {{"type": "shape_design",
    "outer": {{"shape": "circle", "radius": 3.0}},
    "control": {{"inner": {{"shape": "circle", "radius": 2.0}}, "outer": {{"shape": "circle", "radius": 2.5}}}},
    "target": {{"type": "log_radial", "radius": 3.0}}}},
  "initial": {{"shape": "union", "parts": [
    {{"shape": "rectangle", "center": [-{center}, 0.0], "size": [{side}, {side}], "resolution": 32}},
    {{"shape": "rectangle", "center": [{center}, 0.0], "size": [{side}, {side}], "resolution": 32}}]}},
  "flow": {{"max_iterations": {iterations}, "tolerance": 0}}}}"#
    )
}

/// Paper Figure 6: two disjoint squares merge into one curve and J falls by orders
/// of magnitude, to a local minimum that is not the unit circle. The paper's start
/// value 0.08224 (in the `½` convention of Figure 7) is that of two squares of side
/// 3/8 (0.08276); their distance it leaves open: 0.4 from the origin (gap 0.425),
/// as in `examples/design_squares.json`.
#[test]
fn two_squares_merge_into_one_curve() {
    let example =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/design_squares.json")).unwrap();
    let (a, b): (serde_json::Value, serde_json::Value) =
        (serde_json::from_str(&example).unwrap(), serde_json::from_str(&squares(0.375, 0.4, 200)).unwrap());
    assert_eq!(a, b, "the example is the configuration tested here");
    let job = prepared(&example);
    let mut t = Trace(Vec::new());
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut t).unwrap();
    let (j0, j1) = (t.0[0].energy, t.0.last().unwrap().energy);
    assert!((j0 - 0.08224).abs() < 0.01 * 0.08224, "J0 = {j0}");
    assert_eq!(t.0[0].components, 2);
    // they meet within the paper's first dozen or so iterations (it shows the merged
    // curve at k = 12; here the contact step is iteration 14) and stay one curve
    let merged = t.0.iter().position(|p| p.components == 1).expect("the squares never merged");
    assert!(merged <= 20, "merged at iteration {merged}");
    assert!(t.0[merged..].iter().all(|p| p.components == 1));
    assert!(j1 < 1e-4 * j0, "J {j0:e} → {j1:e}");
    // a merge removes the boundary where the curves met, through which the state's
    // flux entered Ω, so J rises at the merge (and after a few re-meshings of the
    // notches it leaves); otherwise it decreases
    let rises: Vec<usize> = (1..t.0.len()).filter(|&k| t.0[k].energy > t.0[k - 1].energy).collect();
    assert!(rises.len() <= 12, "J rose at {rises:?}");
    for &k in &rises {
        assert!(t.0[k].energy < 0.25 * j0, "J rose to {} at {k}", t.0[k].energy);
    }
    // the local minimum is a rounded square with notches where the squares met, not
    // the unit circle (whose radius would vary by < 10 %)
    let last: CurveMesh = out.last.mesh.to_mesh::<2>().unwrap();
    let (area, c, rmin, rmax) = roundness(&last);
    assert!(c.norm() < 0.05, "centroid {c:?}");
    assert!(area > 0.7 * PI && area < 1.1 * PI, "area {area}");
    assert!(rmax / rmin > 1.15, "radius between {rmin} and {rmax}");
}

/// Curves driven into each other merge at their first contact even where the union
/// has a higher J: side 1/2 at ±0.4 crept together with τ → 0 and ended at `tau_min`
/// (J = 1.7e-3 after 31 iterations) before the contact rule of the driver.
#[test]
fn curves_driven_into_contact_merge_instead_of_stalling() {
    let job = prepared(&squares(0.5, 0.4, 150));
    let mut t = Trace(Vec::new());
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut t).unwrap();
    assert_eq!(out.stop, shapeflow::flow::StopReason::MaxIterations);
    assert_eq!(t.0.last().unwrap().components, 1);
    let (j0, j1) = (t.0[0].energy, t.0.last().unwrap().energy);
    assert!(j1 < 1e-3 * j0, "J {j0:e} → {j1:e}");
}

/// Paper §4.3.3 (Figure 8) with a fixed τ = 1 (`examples/design_square.json`): the
/// small circle grows into one smoothed square, aligned with the square ring `D`, and
/// J falls slowly (measured in release: 0.10773 at k = 200, 0.10480 at k = 600; the
/// paper, in our ½ convention: 0.1022 and 0.1000; see docs/problems/shape-design.md for why
/// the last 3 % are out of reach of a single curve). Re-meshings raise J a little
/// (27 times in 600 iterations, each below 3.5e-5).
#[test]
fn square_ring_grows_one_smoothed_square_with_a_fixed_step() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/design_square.json")).unwrap();
    let mut spec: serde_json::Value = serde_json::from_str(&text).unwrap();
    spec["flow"]["max_iterations"] = 600.into();
    spec["flow"]["tau"] = 1.0.into();
    let job = prepared(&spec.to_string());
    let mut t = Trace(Vec::new());
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut t).unwrap();
    let j: Vec<f64> = t.0.iter().map(|p| p.energy).collect();
    assert_eq!(j.len(), 601, "stopped early: {:?}", out.stop);
    assert!(t.0.iter().all(|p| p.components == 1), "the curve split");
    assert!((j[0] - 0.97481 / 2.0).abs() < 5e-3 * j[0], "start {}", j[0]);
    let rises: Vec<f64> = (1..j.len()).filter(|&k| j[k] > j[k - 1]).map(|k| j[k] - j[k - 1]).collect();
    assert!(rises.len() <= 40 && rises.iter().all(|&r| r < 1e-4), "J rose: {rises:?}");
    for k in (100..=600).step_by(100) {
        assert!(j[k] < j[k - 100], "J did not decrease from iteration {} to {k}", k - 100);
    }
    assert!(j[200] > 0.1060 && j[200] < 0.1090, "J(200) = {}", j[200]);
    assert!(j[600] > 0.1040 && j[600] < 0.1056, "J(600) = {}", j[600]);
    // a square aligned with D: r(θ) largest on the diagonals (cos 4θ = −1 there)
    let last: CurveMesh = out.last.mesh.to_mesh::<2>().unwrap();
    let x = last.positions();
    let mode = |k: f64| -> f64 {
        let (mut c, mut total) = (0.0, 0.0);
        for &[a, b] in last.elements() {
            let (ta, tb) = (x[a].y.atan2(x[a].x), x[b].y.atan2(x[b].x));
            let dt = (tb - ta + 3.0 * PI).rem_euclid(2.0 * PI) - PI;
            c += 0.5 * (x[a].norm() + x[b].norm()) * (k * (ta + 0.5 * dt)).cos() * dt;
            total += dt;
        }
        c / total
    };
    let (mean, c4) = (mode(0.0), mode(4.0));
    assert!(mean > 1.0 && mean < 1.8, "mean radius {mean}");
    assert!(c4 < -0.05 * mean, "no square: cos 4θ mode {c4:.4} at mean radius {mean:.4}");
}
