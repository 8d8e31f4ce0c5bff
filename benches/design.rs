//! Shape design (paper §4.3.2, Test 1 domain): time per iteration and its parts —
//! bulk meshing (spade CDT + refinement), the state and adjoint solves (assembly,
//! one sparse Cholesky, two solves) and the whole flow step (which re-solves for
//! every trial step of the backtracking, on the bulk mesh that follows the curve) —
//! for curves of 100, 400 and 1,600 vertices, with the outer boundaries at their
//! default spacing.
//! Memory: peak resident set size after each size. `cargo bench --bench design`.

use shapeflow::bulk::{solve_design_fields, BulkMesh};
use shapeflow::flow::Flow;
use shapeflow::geometry::{ellipse, Point};
use shapeflow::jobs::{parse_spec, prepare, ProblemKind};
use std::collections::HashMap;
use std::time::Instant;

#[path = "common/mod.rs"]
mod common;
use common::{peak_rss_mib, time_it};

fn main() {
    shapeflow::tune_allocator();
    println!("| curve vertices | bulk triangles | meshing | state + adjoint | flow step | step / (mesh + solve) | peak RSS |");
    println!("|---|---|---|---|---|---|---|");
    for n in [100usize, 400, 1600] {
        // Σ and ∂D at the default spacing (1/200 of the perimeter of Σ); the bulk
        // mesh grades from the curve's spacing to it
        let spec = format!(
            r#"{{"problem": {{"type": "shape_design",
                "outer": {{"shape": "circle", "radius": 3.0}},
                "control": {{"inner": {{"shape": "circle", "radius": 2.0}}, "outer": {{"shape": "circle", "radius": 2.5}}}},
                "target": {{"type": "log_radial", "radius": 3.0}}}},
              "initial": {{"shape": "ellipse", "center": [0.5, 0.7], "semi_axes": [0.8, 0.6], "resolution": {n}}},
              "mesh": {{"adapt": false}}}}"#
        );
        let job = prepare(parse_spec(&spec).unwrap(), &HashMap::new()).unwrap();
        let ProblemKind::ShapeDesign(problem) = &job.problem else { unreachable!() };
        let curve = ellipse([0.5, 0.7], [0.8, 0.6], 0.0, n).unwrap();
        let mut bulk = None;
        let t_mesh = time_it(0.5, || bulk = Some(BulkMesh::build(&problem.domain, &curve, &problem.meshing).unwrap()));
        let bulk = bulk.unwrap();
        let target = |x: Point<2>| problem.target.value(x);
        let t_solve = time_it(0.5, || {
            std::hint::black_box(solve_design_fields(&bulk, &target).unwrap());
        });
        // flow steps (a fresh run each time, so that no solution is reused)
        let mut steps = 0usize;
        let start = Instant::now();
        while steps < 5 || start.elapsed().as_secs_f64() < 1.0 {
            let mut run = problem.start();
            let mut flow = Flow::new(&mut run, curve.clone(), job.settings.clone()).unwrap();
            flow.step().unwrap();
            steps += 1;
        }
        // each iteration above also paid one initial energy evaluation
        let t_step = start.elapsed().as_secs_f64() / steps as f64 - (t_mesh + t_solve);
        println!(
            "| {n} | {} | {:.1} ms | {:.1} ms | {:.1} ms | {:.2} | {:.0} MB |",
            bulk.mesh.triangles.len(),
            t_mesh * 1e3,
            t_solve * 1e3,
            t_step * 1e3,
            t_step / (t_mesh + t_solve),
            peak_rss_mib()
        );
    }
}
