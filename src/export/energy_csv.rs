//! The energy history as CSV: `iteration,time,tau,energy,vertices` (plus
//! `components`), one row per accepted iteration.

use crate::flow::Progress;
use std::fmt::Write;

/// CSV text of a history.
pub fn energy_csv(history: &[Progress]) -> String {
    let mut s = String::from("iteration,time,tau,energy,vertices,components\n");
    for p in history {
        let _ = writeln!(s, "{},{:e},{:e},{:e},{},{}", p.iteration, p.time, p.tau, p.energy, p.vertices, p.components);
    }
    s
}
