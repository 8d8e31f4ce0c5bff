//! The epitaxially stressed film (paper §4.4.2): the periodic surface-diffusion
//! limit, conservation and energy decay with the bulk field, and the inclusion.

// libtest starts a binary's tests in the order of their names, two at a time on
// CI's two cores. The wetting layer is the longest test that runs on one thread
// (about 2.5 min of CPU): its module's name puts it first in the engine's binary
// (`film::layer::…`), so the other tests (the two refinement studies run their
// resolutions on threads of their own, then the rest of the engine's tests) share
// the second core beside it instead of leaving it idle at the end.
mod layer;
mod linear;
mod voids;

use shapeflow::export::shape_json;
use shapeflow::flow::{Flow, FlowSettings, MeshData, MeshManager, ScalarProduct};
use shapeflow::geometry::CurveMesh;
use shapeflow::jobs::{parse_spec, prepare, AnyMesh, PreparedJob, ProblemKind};
use shapeflow::problems::{cosine_film, BoundaryData, FilmCell, FilmRun, StressedFilm};
use std::collections::HashMap;
use std::f64::consts::TAU;

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

/// The flow of a film job with its mesh manager (its run lives as long as the test).
fn managed_flow(job: &PreparedJob) -> Flow<'static, 2> {
    let (ProblemKind::StressedFilm(problem), AnyMesh::Curve(mesh)) = (&job.problem, &job.mesh) else { unreachable!() };
    let run: &'static mut FilmRun = Box::leak(Box::new(problem.start()));
    Flow::new(run, mesh.clone(), job.settings.clone())
        .unwrap()
        .with_mesh_manager(Box::new(job.curve_manager.unwrap()) as Box<dyn MeshManager<2>>)
}

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
