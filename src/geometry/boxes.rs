//! Axis-aligned boxes in the plane and a grid that bins many of them, so that the
//! boxes near a point or another box are found without looking at every box
//! (a segmentation's seeds start has thousands of small loops).

/// A closed box `[x_min, y_min, x_max, y_max]`.
pub type Rect = [f64; 4];

/// The box of no point: infinite the wrong way round, so that [`grown`] by a
/// point gives that point's box.
pub const EMPTY: Rect = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];

/// The smallest box holding `b` and `p`.
pub fn grown(b: Rect, p: [f64; 2]) -> Rect {
    [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])]
}

/// The bounding box of `points` ([`EMPTY`] if there are none).
pub fn bounding_box(points: impl Iterator<Item = [f64; 2]>) -> Rect {
    points.fold(EMPTY, grown)
}

/// The intersection of two boxes that meet.
pub fn overlap(a: &Rect, b: &Rect) -> Rect {
    [a[0].max(b[0]), a[1].max(b[1]), a[2].min(b[2]), a[3].min(b[3])]
}

/// Whether the closed boxes `a` and `b` meet.
pub fn boxes_meet(a: &Rect, b: &Rect) -> bool {
    a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3]
}

/// Whether `p` lies in the closed box `b`.
pub fn in_box(b: &Rect, p: [f64; 2]) -> bool {
    p[0] >= b[0] && p[0] <= b[2] && p[1] >= b[1] && p[1] <= b[3]
}

/// Boxes that meet more of a [`BoxGrid`]'s cells than this are not binned but
/// kept in a list of their own, which every query returns: a few long steps of a
/// segmentation's thousands of seeds, their boxes swept across the image, put
/// every box in every cell (about 10⁹ entries, beyond the lists' `u32` indices).
const LARGE: usize = 64;

/// Boxes binned on a grid of about as many cells over them all: every box is
/// listed in each cell it meets (the lists one after the other, a cell's from
/// `start[c]` to `start[c + 1]`), but a box that meets more than [`LARGE`] cells
/// is listed once, apart, and returned by every query.
pub struct BoxGrid {
    origin: [f64; 2],
    cell: [f64; 2],
    side: usize,
    start: Vec<u32>,
    listed: Vec<u32>,
    large: Vec<u32>,
}

impl BoxGrid {
    pub fn new(boxes: &[Rect]) -> BoxGrid {
        let all = bounding_box(boxes.iter().flat_map(|b| [[b[0], b[1]], [b[2], b[3]]]));
        let side = ((boxes.len() as f64).sqrt().ceil() as usize).clamp(1, 256);
        let cell = [((all[2] - all[0]) / side as f64).max(1e-300), ((all[3] - all[1]) / side as f64).max(1e-300)];
        let mut grid = BoxGrid {
            origin: [all[0], all[1]],
            cell,
            side,
            start: vec![0; side * side + 1],
            listed: Vec::new(),
            large: Vec::new(),
        };
        // count the boxes of each cell, then list them in place; a large box gets
        // the empty range [1, 1, 0, 0] and goes to its own list
        let ranges: Vec<[usize; 4]> = boxes
            .iter()
            .enumerate()
            .map(|(k, b)| {
                let (lo, hi) = (grid.index([b[0], b[1]]), grid.index([b[2], b[3]]));
                if (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) > LARGE {
                    grid.large.push(k as u32);
                    return [1, 1, 0, 0];
                }
                [lo[0], lo[1], hi[0], hi[1]]
            })
            .collect();
        for &[x0, y0, x1, y1] in &ranges {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    grid.start[y * side + x + 1] += 1;
                }
            }
        }
        for c in 0..side * side {
            grid.start[c + 1] += grid.start[c];
        }
        let mut next: Vec<u32> = grid.start[..side * side].to_vec();
        grid.listed = vec![0; grid.start[side * side] as usize];
        for (k, &[x0, y0, x1, y1]) in ranges.iter().enumerate() {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * side + x;
                    grid.listed[next[c] as usize] = k as u32;
                    next[c] += 1;
                }
            }
        }
        grid
    }

    fn index(&self, p: [f64; 2]) -> [usize; 2] {
        let at = |d: usize| (((p[d] - self.origin[d]) / self.cell[d]).max(0.0) as usize).min(self.side - 1);
        [at(0), at(1)]
    }

    fn cell(&self, c: usize) -> &[u32] {
        &self.listed[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// The boxes listed in the cell of `p` and the large ones (every box that
    /// holds `p` among them).
    pub fn at(&self, p: [f64; 2]) -> impl Iterator<Item = usize> + '_ {
        let [x, y] = self.index(p);
        self.large.iter().chain(self.cell(y * self.side + x)).map(|&k| k as usize)
    }

    /// The boxes listed in the cells that `b` meets, a box once for each such
    /// cell, and the large ones once (every box that meets `b` among them).
    pub fn near(&self, b: &Rect) -> impl Iterator<Item = usize> + '_ {
        let (lo, hi) = (self.index([b[0], b[1]]), self.index([b[2], b[3]]));
        let binned = (lo[1]..=hi[1]).flat_map(move |y| {
            (lo[0]..=hi[0]).flat_map(move |x| self.cell(y * self.side + x).iter().map(|&k| k as usize))
        });
        self.large.iter().map(|&k| k as usize).chain(binned)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boxes near a box are found by the grid exactly as by looking at all,
    /// the large boxes (kept apart from the cells) among them.
    #[test]
    fn the_grid_finds_every_box_that_meets() {
        let mut boxes: Vec<Rect> = (0..400)
            .map(|k| {
                let (x, y) = ((k % 20) as f64 * 1.5, (k / 20) as f64 * 1.5 + 0.1 * (k % 3) as f64);
                [x, y, x + 1.0 + 0.5 * (k % 4) as f64, y + 1.0]
            })
            .collect();
        // across everything, along a row, down a column, and a quarter
        boxes.extend([
            [-1.0, -1.0, 40.0, 40.0],
            [0.0, 7.2, 30.0, 7.4],
            [12.1, 0.0, 12.2, 30.0],
            [0.0, 0.0, 15.0, 15.0],
        ]);
        let grid = BoxGrid::new(&boxes);
        // (21 × 21 cells of about 2 × 2: the row and the column meet 16 each)
        assert_eq!(grid.large, [400, 403]);
        for (i, b) in boxes.iter().enumerate() {
            let mut found: Vec<usize> = grid.near(b).filter(|&j| boxes_meet(b, &boxes[j])).collect();
            found.sort_unstable();
            found.dedup();
            let all: Vec<usize> = (0..boxes.len()).filter(|&j| boxes_meet(b, &boxes[j])).collect();
            assert_eq!(found, all, "box {i}");
            let p = [b[0] + 0.25, b[1] + 0.25];
            let mut holding: Vec<usize> = grid.at(p).filter(|&j| in_box(&boxes[j], p)).collect();
            holding.sort_unstable();
            assert_eq!(holding, (0..boxes.len()).filter(|&j| in_box(&boxes[j], p)).collect::<Vec<_>>());
        }
        assert_eq!(bounding_box([[1.0, 2.0], [-1.0, 5.0]].into_iter()), [-1.0, 2.0, 1.0, 5.0]);
    }
}
