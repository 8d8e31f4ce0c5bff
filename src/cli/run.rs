//! `shapeflow run`: a job spec run offline, with a progress bar, its result files
//! written to a directory.

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use shapeflow::flow::{Checkpoint, Progress};
use shapeflow::jobs::{output_files, parse_spec, prepare, run_with_frames, RunEvents};
use std::collections::HashMap;
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;

struct Reporter {
    bar: ProgressBar,
    history: Vec<Progress>,
    end_time: Option<f64>,
}

impl RunEvents for Reporter {
    fn progress(&mut self, p: &Progress) {
        self.history.push(*p);
        match self.end_time {
            Some(t) => self.bar.set_position((1000.0 * p.time / t).round() as u64),
            None => self.bar.set_position(p.iteration as u64),
        }
        self.bar.set_message(format!("J={:.6e} τ={:.2e} t={:.4e} n={}", p.energy, p.tau, p.time, p.vertices));
    }
}

pub(crate) fn run(spec_path: &Path, out: &Path, inputs: &[String], resume: Option<&Path>) -> Result<ExitCode> {
    let text =
        std::fs::read_to_string(spec_path).with_context(|| format!("cannot read spec {}", spec_path.display()))?;
    let spec = parse_spec(&text).with_context(|| format!("invalid spec {}", spec_path.display()))?;
    let mut files = HashMap::new();
    for item in inputs {
        let (name, path) = item.split_once('=').with_context(|| format!("--input {item:?}: expected NAME=PATH"))?;
        let bytes = std::fs::read(path).with_context(|| format!("--input {name}: cannot read {path}"))?;
        files.insert(name.to_string(), bytes);
    }
    let started = std::time::Instant::now();
    let job = prepare(spec, &files).with_context(|| format!("invalid spec {}", spec_path.display()))?;
    let prepared = started.elapsed();
    let checkpoint: Option<Checkpoint> = match resume {
        Some(p) => {
            let t = std::fs::read_to_string(p).with_context(|| format!("cannot read checkpoint {}", p.display()))?;
            Some(serde_json::from_str(&t).with_context(|| format!("invalid checkpoint {}", p.display()))?)
        }
        None => None,
    };
    std::fs::create_dir_all(out).with_context(|| format!("cannot create output directory {}", out.display()))?;
    let s = &job.settings;
    let len = if s.end_time.is_some() { 1000 } else { s.max_iterations as u64 };
    let bar = ProgressBar::new(len);
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} {msg} [{elapsed}]").expect("template"));
    let cancel = AtomicBool::new(false);
    let ran = std::time::Instant::now();
    // the checkpoints' frames (their fields and drawing) are made on a second thread
    // while the run goes on
    let mut rep = Reporter { bar, history: Vec::new(), end_time: s.end_time };
    let (result, frames) = run_with_frames(&job, checkpoint.as_ref(), &cancel, &mut rep);
    rep.bar.finish_and_clear();
    let ran = ran.elapsed();
    let (last, code) = match result {
        Ok(o) => {
            say(format_args!(
                "stopped: {} after {} iterations (time {:.6e}, energy {:.9e})",
                o.stop.as_str(),
                o.last.iteration,
                o.last.time,
                o.last.energy
            ));
            if let Some(note) = o.note {
                say(format_args!("  {note}"));
            }
            (o.last, ExitCode::SUCCESS)
        }
        Err(f) => {
            eprintln!("failed: {}", f.error);
            (f.last, ExitCode::from(1))
        }
    };
    let writing = std::time::Instant::now();
    // the result files of the run's frames (the last one its final state), the VTK
    // time series unpacked beside its zip, the history, and checkpoint.json with
    // the flow's state for --resume
    let mut written = Vec::new();
    for (name, bytes) in output_files(&job, &frames, &rep.history, &last, &spec_path.display().to_string()) {
        let p = out.join(&name);
        if let Some(dir) = p.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        std::fs::write(&p, bytes).with_context(|| format!("cannot write {}", p.display()))?;
        if !name.starts_with("evolution/") {
            written.push(name);
        }
    }
    say(format_args!("wrote {} in {}", written.join(", "), out.display()));
    say(format_args!(
        "took {:.3} s to prepare (inputs decoded, preprocessed, initial shape), {:.3} s to run, {:.3} s to write the results",
        prepared.as_secs_f64(),
        ran.as_secs_f64(),
        writing.elapsed().as_secs_f64()
    ));
    Ok(code)
}

/// A line on stdout; a closed pipe (`shapeflow run … | head -1`) is not an error
/// (the results are written whatever happens to the report).
pub(crate) fn say(line: std::fmt::Arguments) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout(), "{line}");
}
