//! Two stages, and the Newton-type H1 product against L2.

use super::*;

#[test]
fn a_second_stage_without_balloon_force_sharpens_the_contour() {
    let p = picture(128, 128, 12.0, 7, star(64.0, 64.0, 34.0, 0.3, 5.0));
    let img = png_gray8(&p);
    let (job, out, history) = run_with_history(
        r#"{"initial": {"shape": "inscribed"}, "problem": {"type": "segmentation", "image": "input:image", "model": "geodesic"}}"#,
        &[("image", img.clone())],
    );
    let one = r#"{"initial": {"shape": "inscribed"}, "problem": {"type": "segmentation", "image": "input:image", "model": "geodesic", "lambda_final": 38.4}}"#;
    let (job1, out1) = run(one, &[("image", img.clone())]);
    assert!(job1.second_stage.is_none(), "lambda_final = lambda: one stage");
    let (d2, d1) = (dice(&job, &out.last.mesh, &p.truth, 128, 128), dice(&job1, &out1.last.mesh, &p.truth, 128, 128));
    eprintln!(
        "one stage: {} iterations, dice {d1:.4}; two: {} iterations, dice {d2:.4}",
        out1.last.iteration, out.last.iteration
    );
    assert_eq!((out.stop, out1.stop), (StopReason::Converged, StopReason::Converged));
    assert!(d2 >= 0.993 && d2 > d1 + 0.004, "dice {d2} with the second stage, {d1} without");
    // the first stage is the one-stage run; the second is short and continues it
    assert_eq!(out.last.stage, 1);
    assert_eq!(history.len(), out.last.iteration + 1, "one progress report per iteration");
    let switch = out1.last.iteration;
    assert!(out.last.iteration > switch && out.last.iteration <= switch + 20, "{} after {switch}", out.last.iteration);
    assert!(
        history[switch + 1] < 0.01 * history[switch],
        "the region term is gone: {:?}",
        &history[switch..switch + 2]
    );
    // a checkpoint of the second stage resumes in it
    let mut cps: Vec<Checkpoint> = Vec::new();
    let job = prepare(
        parse_spec(
            r#"{"initial": {"shape": "inscribed"}, "problem": {"type": "segmentation", "image": "input:image", "model": "geodesic"}, "output": {"checkpoint_every": 1}}"#,
        )
        .unwrap(),
        &[("image".to_string(), img)].into(),
    )
    .unwrap();
    run_prepared(&job, None, &AtomicBool::new(false), &mut cps).unwrap();
    let mid = cps.iter().find(|c| c.stage == 1 && c.iteration > switch + 1).expect("a checkpoint in the second stage");
    let resumed = run_prepared(&job, Some(mid), &AtomicBool::new(false), &mut ()).unwrap();
    assert_eq!(resumed.last.stage, 1);
    assert!(
        (resumed.last.energy - out.last.energy).abs() < 1e-3 * out.last.energy,
        "{} {}",
        resumed.last.energy,
        out.last.energy
    );
}

/// Paper Figure 1: on a C-shaped object both flows find the object; the Newton-type
/// H1 flow gets within 1e-5 of the best energy in fewer iterations than L2, and
/// within 1e-6 in less than 0.6 of them (one stage, `lambda_final` = `lambda`, the
/// default 0.3 L; the paper's edge indicator, `k` = 1 on the image mapped to [0, 100]).
#[test]
fn newton_h1_and_l2_on_a_c_shape() {
    let p = picture(128, 128, 12.0, 7, c_shape(64.0, 64.0, 40.0, 22.0, 10.0));
    let img = png_gray8(&p);
    let spec = |prod: &str| {
        format!(
            r#"{{"initial": {{"shape": "inscribed"}}, "problem": {{"type": "segmentation", "image": "input:image", "model": "geodesic", "edge_contrast": 1, "lambda_final": 38.4}}, "flow": {{"scalar_product": "{prod}", "max_iterations": 1500, "tolerance": 1e-10}}}}"#
        )
    };
    let (ja, a, ha) = run_with_history(&spec("h1_newton"), &[("image", img.clone())]);
    let (jb, b, hb) = run_with_history(&spec("l2"), &[("image", img)]);
    let best = a.last.energy.min(b.last.energy);
    let reach_to = |h: &[f64], t: f64| h.iter().position(|&e| e <= best * (1.0 + t)).unwrap_or(usize::MAX);
    let reach = |h: &[f64]| reach_to(h, 1e-5);
    let (da, db) = (dice(&ja, &a.last.mesh, &p.truth, 128, 128), dice(&jb, &b.last.mesh, &p.truth, 128, 128));
    let (na, nb) = (reach_to(&ha, 1e-6), reach_to(&hb, 1e-6));
    eprintln!(
        "newton: {} iterations to 1e-5, {na} to 1e-6, dice {da:.4}; l2: {} and {nb}, dice {db:.4}",
        reach(&ha),
        reach(&hb)
    );
    assert!(da >= 0.98 && db >= 0.98);
    assert!(nb < usize::MAX, "both flows come within 1e-6 of the best energy");
    assert!(reach(&ha) < reach(&hb), "newton {} l2 {}", reach(&ha), reach(&hb));
    // the approach is limited by the step control in both flows; the last digits
    // are where the Newton-type product pays
    assert!((na as f64) < 0.6 * nb as f64, "to 1e-6: newton {na} l2 {nb}");
}
