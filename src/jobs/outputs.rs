//! What a run writes to a directory (the CLI's `--out`, Python's `Result.save`):
//! the result files ([`result_files`]), the VTK time series unpacked
//! (`evolution.pvd`, `evolution/frame_NNNNN.vtp`), the energy history (CSV and
//! SVG) and the last state (`checkpoint.json`, for a resume).

use super::frames::Frame;
use super::results::result_files;
use super::vtk_files::vtk_series;
use super::PreparedJob;
use crate::export::{energy_csv, energy_svg};
use crate::flow::{Checkpoint, Progress};

/// The files of a run, as (path relative to the output directory, bytes):
/// `history` is every progress report, `last` the final state and `title` the
/// energy plot's title.
pub fn output_files(
    job: &PreparedJob,
    frames: &[Frame],
    history: &[Progress],
    last: &Checkpoint,
    title: &str,
) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> =
        result_files(job, frames).into_iter().map(|f| (f.name.into_owned(), f.bytes)).collect();
    files.extend(vtk_series(job, frames));
    files.push(("energy.csv".into(), energy_csv(history).into_bytes()));
    files.push(("energy.svg".into(), energy_svg(history, title).into_bytes()));
    files.push(("checkpoint.json".into(), serde_json::to_vec(last).expect("checkpoints serialize")));
    files
}
