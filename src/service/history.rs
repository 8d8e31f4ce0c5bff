//! Which history rows a job keeps: every row of its first [`HISTORY_ROWS`]
//! iterations, then every second, fourth, … row as the run gets longer (the
//! stride the smallest power of two at least `iteration / HISTORY_ROWS + 1`),
//! and always the rows where the number of components changes (a topological
//! change) and the run's last row. So the rows of a job grow with the logarithm
//! of its length: at most about 430,000 for the largest `flow.max_iterations`
//! (10⁸), whatever the checkpoints.

use crate::flow::Progress;

/// Iterations whose every row is kept.
pub const HISTORY_ROWS: usize = 65_536;

/// The rows' thinning of one run.
#[derive(Debug, Default)]
pub(super) struct Thinning {
    components: Option<usize>,
    skipped: Option<Progress>,
}

impl Thinning {
    /// Whether to keep the row `p` (rows come in iteration order).
    pub fn keep(&mut self, p: &Progress) -> bool {
        let changed = self.components.is_some_and(|c| c != p.components);
        self.components = Some(p.components);
        let keep = changed || p.surgery.is_some() || p.iteration % stride(p.iteration) == 0;
        self.skipped = if keep { None } else { Some(*p) };
        keep
    }

    /// The last row seen, if it was not kept: the run's last row, kept at its end.
    pub fn last_skipped(&mut self) -> Option<Progress> {
        self.skipped.take()
    }
}

/// The stride of the rows kept around `iteration`.
fn stride(iteration: usize) -> usize {
    if iteration < HISTORY_ROWS {
        1
    } else {
        (iteration / HISTORY_ROWS + 1).next_power_of_two()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(iteration: usize, components: usize) -> Progress {
        Progress { iteration, time: 0.0, tau: 1.0, energy: 1.0, vertices: 8, components, surgery: None }
    }

    #[test]
    fn rows_are_all_kept_then_thinned_with_topology_changes_and_the_last_kept() {
        let mut t = Thinning::default();
        let n = 100_000_000;
        let mut kept = 0usize;
        let mut last_kept = 0;
        for it in 0..n {
            // a component appears at one iteration, off every stride
            let components = if it >= 77_777_777 { 2 } else { 1 };
            if t.keep(&row(it, components)) {
                kept += 1;
                last_kept = it;
                if it < HISTORY_ROWS {
                    assert_eq!(kept, it + 1);
                }
            }
            if it == 77_777_777 {
                assert_eq!(last_kept, it, "a topological change is kept");
            }
        }
        assert!(kept < 430_000, "{kept} rows");
        assert_eq!(t.last_skipped().map(|p| p.iteration), Some(n - 1), "the last row is handed back");
        assert!(last_kept < n - 1);
    }
}
