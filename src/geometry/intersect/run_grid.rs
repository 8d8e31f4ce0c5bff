//! The uniform grid of [`super::find_segment_intersections`]: the runs of
//! consecutive segments that meet each cell, and a table from cells to runs.

use super::super::Point;

/// A maximal run of consecutive segments `first..=last` (each starting where the
/// one before ended) whose bounding boxes all meet one grid cell.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Run {
    pub(crate) cell: u64,
    pub(crate) first: u32,
    pub(crate) last: u32,
}

/// The runs of a set of segments on a grid of square cells, and a table from cells
/// to their runs (chained slots, cells tiled modulo the table's side so that a
/// curve walking through neighbouring cells walks through neighbouring slots).
pub(crate) struct RunGrid {
    /// Side of a cell: 4× (or the `scale` of [`RunGrid::build_scaled`]) the mean
    /// max-norm segment length.
    pub(crate) side: f64,
    pub(crate) runs: Vec<Run>,
    /// Segments meeting more than 64 cells (far longer than the mean).
    pub(crate) long: Vec<usize>,
    bits: u32,
    head: Vec<u32>,
    next: Vec<u32>,
}

const NONE: u32 = u32::MAX;

/// `(cx, cy)` packed into one key.
pub(crate) fn pack(cx: u32, cy: u32) -> u64 {
    (u64::from(cx) << 32) | u64::from(cy)
}

impl RunGrid {
    /// Walks the segments in order; `ids` (if given) maps point indices to vertex
    /// identities for the test whether a segment continues the one before.
    pub(crate) fn build(points: &[Point<2>], segments: &[[usize; 2]], ids: Option<&[usize]>) -> RunGrid {
        Self::build_scaled(points, segments, ids, 4.0)
    }

    /// [`RunGrid::build`] with cells of `scale` times the mean max-norm segment length.
    pub(crate) fn build_scaled(
        points: &[Point<2>],
        segments: &[[usize; 2]],
        ids: Option<&[usize]>,
        scale: f64,
    ) -> RunGrid {
        let id = |v: usize| ids.map_or(v, |ids| ids[v]);
        // the lower corner of all boxes, and the cell side
        let (mut total, mut x_lo, mut y_lo) = (0.0, f64::INFINITY, f64::INFINITY);
        for s in segments {
            let (p, q) = (points[s[0]], points[s[1]]);
            total += (q.x - p.x).abs().max((q.y - p.y).abs());
            x_lo = x_lo.min(p.x.min(q.x));
            y_lo = y_lo.min(p.y.min(q.y));
        }
        let side = (scale * total / segments.len().max(1) as f64).max(1e-300);
        let inv = 1.0 / side;
        // coordinates shifted to be nonnegative, so truncation is floor
        let key = |x: f64, lo: f64| ((x - lo) * inv) as u32;
        let mut runs: Vec<Run> = Vec::with_capacity(segments.len() / 2 + 8);
        let mut long = Vec::new();
        // (cell, run) of the segment before, at most 64 cells
        let mut before: Vec<(u64, usize)> = Vec::with_capacity(64);
        let mut now: Vec<(u64, usize)> = Vec::with_capacity(64);
        for (i, s) in segments.iter().enumerate() {
            let (p, q) = (points[s[0]], points[s[1]]);
            let (x0, x1) = (key(p.x.min(q.x), x_lo), key(p.x.max(q.x), x_lo));
            let (y0, y1) = (key(p.y.min(q.y), y_lo), key(p.y.max(q.y), y_lo));
            if (u64::from(x1 - x0) + 1) * (u64::from(y1 - y0) + 1) > 64 {
                long.push(i);
                before.clear();
                continue;
            }
            let continues = i > 0 && {
                let b = segments[i - 1][1];
                id(b) == id(s[0]) && points[b] == p
            };
            now.clear();
            for cx in x0..=x1 {
                for cy in y0..=y1 {
                    let c = pack(cx, cy);
                    let open = if continues { before.iter().find(|(b, _)| *b == c).map(|&(_, r)| r) } else { None };
                    let r = match open {
                        Some(r) => {
                            runs[r].last = i as u32;
                            r
                        }
                        None => {
                            runs.push(Run { cell: c, first: i as u32, last: i as u32 });
                            runs.len() - 1
                        }
                    };
                    now.push((c, r));
                }
            }
            std::mem::swap(&mut before, &mut now);
        }
        let bits = (4 * runs.len()).next_power_of_two().trailing_zeros().div_ceil(2);
        let mut grid = RunGrid { side, runs, long, bits, head: vec![NONE; 1usize << (2 * bits)], next: Vec::new() };
        grid.next = vec![NONE; grid.runs.len()];
        for k in 0..grid.runs.len() {
            let slot = grid.slot(grid.runs[k].cell);
            grid.next[k] = grid.head[slot];
            grid.head[slot] = k as u32;
        }
        grid
    }

    fn slot(&self, c: u64) -> usize {
        let side = (1u64 << self.bits) - 1;
        (((c & side) << self.bits) | ((c >> 32) & side)) as usize
    }

    /// The runs in cell `c` (a packed key), latest first.
    pub(crate) fn cell_runs(&self, c: u64) -> impl Iterator<Item = usize> + '_ {
        let mut e = self.head[self.slot(c)];
        std::iter::from_fn(move || {
            while e != NONE {
                let k = e as usize;
                e = self.next[k];
                if self.runs[k].cell == c {
                    return Some(k);
                }
            }
            None
        })
    }
}
