//! The stressed film (examples/stressed_film.json): refinement study of the time
//! at which the first void closes off, with the film's area drift and J up to
//! then, and the cost per step (bulk meshing + field solve + surface step), for
//! 64, 128 and 256 vertices (`cargo bench --bench film [-- 64 128]`).

use shapeflow::flow::{Flow, MeshManager};
use shapeflow::jobs::{parse_spec, prepare, AnyMesh, ProblemKind};
use std::collections::HashMap;
use std::time::Instant;

#[path = "common/mod.rs"]
mod common;
use common::peak_rss_mib;

fn main() {
    shapeflow::tune_allocator();
    let sizes: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let sizes = if sizes.is_empty() { vec![64, 128, 256] } else { sizes };
    let example = std::fs::read_to_string("examples/stressed_film.json").unwrap();
    println!("| vertices | first void at t | void area | film area drift | J(0) → J | steps | ms / step | peak RSS |");
    println!("|---|---|---|---|---|---|---|---|");
    for n in sizes {
        let spec = example
            .replace("\"resolution\": 128", &format!("\"resolution\": {n}"))
            .replace("\"end_time\": 0.0067", "\"end_time\": 0.0085");
        let job = prepare(parse_spec(&spec).unwrap(), &HashMap::new()).unwrap();
        let (ProblemKind::StressedFilm(problem), AnyMesh::Curve(mesh)) = (&job.problem, &job.mesh) else {
            unreachable!()
        };
        let mut run = problem.start();
        let mut flow = Flow::new(&mut run, mesh.clone(), job.settings.clone())
            .unwrap()
            .with_mesh_manager(Box::new(job.curve_manager.unwrap()) as Box<dyn MeshManager<2>>);
        let (area0, energy0) = (flow.mesh().enclosed_measure(), flow.energy());
        let start = Instant::now();
        let mut steps = 0;
        let found = loop {
            match flow.step() {
                Ok(r) if r.stop.is_some() => break None,
                Ok(_) => {}
                Err(e) => {
                    println!("| {n} | failed: {e} |");
                    break None;
                }
            }
            steps += 1;
            let c = flow.mesh();
            if let Some(((p, _), _)) = c.lifted_cycles().iter().zip(c.windings()).find(|(_, w)| *w == 0) {
                let m = p.len();
                let area: f64 = (0..m).map(|k| 0.5 * (p[k].x * p[(k + 1) % m].y - p[(k + 1) % m].x * p[k].y)).sum();
                break Some((flow.time(), area));
            }
        };
        let ms = 1e3 * start.elapsed().as_secs_f64() / steps.max(1) as f64;
        let drift = flow.mesh().enclosed_measure() / area0 - 1.0;
        match found {
            Some((t, area)) => println!(
                "| {n} | {t:.5} | {area:.2e} | {drift:.1e} | {energy0:.4} → {:.4} | {steps} | {ms:.1} | {:.0} MiB |",
                flow.energy(),
                peak_rss_mib()
            ),
            None => println!("| {n} | no void by t = {:.5} | | {drift:.1e} | | {steps} | {ms:.1} | |", flow.time()),
        }
    }
}
