//! Surface diffusion of the 8×1×1 prism (paper §4.4.1) runs to pinch-off with mesh
//! management keeping the triangles sound.

use shapeflow::flow::{Checkpoint, Progress, StopReason};
use shapeflow::jobs::{parse_spec, prepare, run_prepared, RunEvents};
use std::collections::HashMap;
use std::sync::atomic::AtomicBool;

struct Watch {
    /// (time, min angle, max angle) at every checkpoint
    angles: Vec<(f64, f64, f64)>,
    vertices: (usize, usize),
    last: Option<Checkpoint>,
}

impl RunEvents for Watch {
    fn progress(&mut self, p: &Progress) {
        self.vertices = (self.vertices.0.min(p.vertices), self.vertices.1.max(p.vertices));
    }
    fn checkpoint(&mut self, c: &Checkpoint) {
        let m = c.mesh.to_mesh::<3>().expect("every checkpoint is a valid closed surface");
        let q = m.quality();
        self.angles.push((c.time, q.min_angle_deg, q.max_angle_deg));
        self.last = Some(c.clone());
    }
}

#[test]
fn prism_surface_diffusion_reaches_pinch_off() {
    let spec = parse_spec(
        r#"{"problem": {"type": "surface_diffusion"},
            "initial": {"shape": "box", "size": [8.0, 1.0, 1.0], "resolution": 8},
            "flow": {"tau": 5e-4, "step_control": 0.1, "end_time": 0.6, "max_iterations": 100000},
            "mesh": {"h_max": 0.2},
            "output": {"checkpoint_every": 1}}"#,
    )
    .unwrap();
    let job = prepare(spec, &HashMap::new()).unwrap();
    let mut w = Watch { angles: Vec::new(), vertices: (usize::MAX, 0), last: None };
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut w).unwrap();
    let last = w.last.unwrap();
    // neck radius at the centre of the final shape
    let neck =
        last.mesh.positions.iter().filter(|p| p[0].abs() < 0.1).map(|p| p[1].hypot(p[2])).fold(f64::INFINITY, f64::min);
    // triangle quality over the whole run, up to the pinch (every step)
    for a in w.angles.iter().filter(|a| a.1 < 15.0) {
        eprintln!("checkpoint at t = {:.5}: angles [{:.1}, {:.1}]", a.0, a.1, a.2);
    }
    let min_angle = w.angles.iter().map(|a| a.1).fold(180.0, f64::min);
    let max_angle = w.angles.iter().map(|a| a.2).fold(0.0, f64::max);
    let early = w.angles.iter().filter(|a| a.0 < 0.97 * last.time).map(|a| a.1).fold(180.0, f64::min);
    eprintln!(
        "stop {:?} at t = {:.4}, neck radius {neck:.4}, vertices {:?}, angles [{min_angle:.1}, {max_angle:.1}] ({early:.1} before the final 3 %)",
        out.stop, last.time, w.vertices
    );
    assert_eq!(out.stop, StopReason::PinchOff);
    assert!(neck < 0.1, "a thin neck at the centre: {neck}");
    // every step's mesh (checkpoint_every = 1), up to the last good state before the
    // pinch, keeps its angles above 10°
    assert!(min_angle > 10.0, "minimum angle {min_angle}");
    assert!(early > 25.0, "minimum angle before the final collapse {early}");
    assert!(w.vertices.0 >= 1000 && w.vertices.1 <= 2500, "vertex counts of the paper's order: {:?}", w.vertices);
    // the paper reports t ≈ 0.4135; we reach the pinch somewhat earlier (see docs/problems/surface-evolution.md)
    assert!(last.time > 0.33 && last.time < 0.45, "pinch-off time {}", last.time);
}

/// Pinch-off time of the prism with the example's settings at a given `resolution`
/// (elements per unit length of the initial box).
fn pinch_time(resolution: usize) -> f64 {
    let spec = parse_spec(&format!(
        r#"{{"problem": {{"type": "surface_diffusion"}},
            "initial": {{"shape": "box", "size": [8.0, 1.0, 1.0], "resolution": {resolution}}},
            "flow": {{"tau": 5e-4, "step_control": 0.1, "end_time": 0.6, "max_iterations": 100000}},
            "mesh": {{"h_max": 0.2}},
            "output": {{"checkpoint_every": 100000}}}}"#
    ))
    .unwrap();
    let job = prepare(spec, &HashMap::new()).unwrap();
    let mut w = Watch { angles: Vec::new(), vertices: (usize::MAX, 0), last: None };
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut w).unwrap();
    assert_eq!(out.stop, StopReason::PinchOff, "resolution {resolution}");
    // the last checkpoint is the last good state before the pinch
    w.last.unwrap().time
}

#[test]
fn pinch_off_time_is_stable_under_refinement() {
    let times: Vec<f64> = std::thread::scope(|s| {
        let runs: Vec<_> = [6, 8, 12].into_iter().map(|r| s.spawn(move || pinch_time(r))).collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    eprintln!("pinch-off at t = {times:.4?} (resolutions 6, 8, 12)");
    let (lo, hi) = (times.iter().copied().fold(f64::INFINITY, f64::min), times.iter().copied().fold(0.0, f64::max));
    assert!(hi - lo < 0.02 * lo, "pinch-off times {times:?} spread by 2 % or more");
    // converged in space and time (and by an independent axisymmetric solver, see
    // docs/problems/surface-evolution.md) the pinch is at 0.3675; the paper reports 0.4135
    assert!(times.iter().all(|&t| (0.36..0.39).contains(&t)), "{times:?}");
}
