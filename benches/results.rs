//! Writing the result files of a run, and the VTK files' share of it: for three
//! example jobs (a curve flow, a 2D and a 3D segmentation), the time of every file
//! the CLI writes (`jobs::output_files`: shape.json/.glb/.vtp, evolution.glb, the
//! VTK time series as evolution.pvd with its frames and as evolution_vtk.zip, the
//! image results, the history) against that of the VTK files alone (shape.vtp, the
//! series, its zip). `cargo bench --bench results`.

use shapeflow::flow::Progress;
use shapeflow::jobs::{
    frame_vtp, output_files, parse_spec, prepare, run_with_frames, vtk_series, zip_files, RunEvents,
};
use std::collections::HashMap;
use std::sync::atomic::AtomicBool;

#[path = "common/mod.rs"]
mod common;
use common::time_it;

#[derive(Default)]
struct History(Vec<Progress>);

impl RunEvents for History {
    fn progress(&mut self, p: &Progress) {
        self.0.push(*p);
    }
}

fn main() {
    shapeflow::tune_allocator();
    let repo = env!("CARGO_MANIFEST_DIR");
    let jobs = [
        ("circle (curvature flow)", "examples/circle.json", None),
        ("segment_four (2D image)", "examples/segment_four.json", Some(("image", "examples/data/four.png"))),
        ("segment_balls (3D volume)", "examples/segment_balls.json", Some(("volume", "examples/data/balls.nrrd"))),
    ];
    println!("| job | frames | vertices (last) | all files | VTK files | VTK share | of them the zip |");
    println!("|---|---|---|---|---|---|---|");
    for (name, spec, input) in jobs {
        let text = std::fs::read_to_string(format!("{repo}/{spec}")).expect("the example");
        let inputs: HashMap<String, Vec<u8>> = input
            .map(|(k, path)| (k.to_string(), std::fs::read(format!("{repo}/{path}")).expect("the example's input")))
            .into_iter()
            .collect();
        let job = prepare(parse_spec(&text).expect("the example parses"), &inputs).expect("the example prepares");
        let mut history = History::default();
        let (outcome, frames) = run_with_frames(&job, None, &AtomicBool::new(false), &mut history);
        let last = outcome.expect("the example runs").last;
        let all = time_it(1.0, || {
            std::hint::black_box(output_files(&job, &frames, &history.0, &last, name));
        });
        let vtk = time_it(1.0, || {
            let series = vtk_series(&job, &frames);
            std::hint::black_box((frame_vtp(&job, frames.last().unwrap()), zip_files(&series), series));
        });
        let series = vtk_series(&job, &frames);
        let zip = time_it(0.5, || {
            std::hint::black_box(zip_files(&series));
        });
        let vertices = frames.last().map_or(0, |f| f.state.mesh.positions.len());
        println!(
            "| {name} | {} | {vertices} | {:.1} ms | {:.1} ms | {:.0} % | {:.1} ms |",
            frames.len(),
            all * 1e3,
            vtk * 1e3,
            100.0 * vtk / all,
            zip * 1e3
        );
    }
}
