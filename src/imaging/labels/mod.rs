//! Binary masks and label images on a grid (`x` fastest, as [`super::Grid`]):
//! connected components and hole filling here; the Euclidean distance transform
//! (`distance`), the split of touching objects by a persistence watershed on
//! it (`watershed`), the holes the region model keeps open (`holes`), and the
//! territory of every object (`territory`). Face
//! neighbours (4 in 2D, 6 in 3D) throughout. Labels are `1..=count`, 0 is
//! background.

mod distance;
mod holes;
mod peaks;
mod territory;
mod watershed;

pub use distance::distance_transform;
pub use holes::{reopen_holes, RegionWeights};
pub use peaks::split_at_peaks;
pub use territory::territories;
pub use watershed::{flood_from_cores, separate, split_at_ridges, split_touching, Necks};

/// Grid dimensions `[n_x, n_y, n_z]` (`n_z = 1` in 2D).
pub type Dims = [usize; 3];

/// The face neighbours of sample `p` (at most 6).
fn neighbours(dims: Dims, p: usize, out: &mut Vec<usize>) {
    out.clear();
    let [nx, ny, nz] = dims;
    let (i, j, k) = (p % nx, (p / nx) % ny, p / (nx * ny));
    if i > 0 {
        out.push(p - 1);
    }
    if i + 1 < nx {
        out.push(p + 1);
    }
    if j > 0 {
        out.push(p - nx);
    }
    if j + 1 < ny {
        out.push(p + nx);
    }
    if k > 0 {
        out.push(p - nx * ny);
    }
    if k + 1 < nz {
        out.push(p + nx * ny);
    }
}

/// Connected components of `mask`: a label per sample and the number of labels,
/// numbered in the order of each component's first sample. Runs of consecutive
/// samples along `x` are joined (union–find) with the runs they overlap in the
/// row before and in the same row of the slice before.
pub fn components(mask: &[bool], dims: Dims) -> (Vec<u32>, usize) {
    let [nx, ny, nz] = dims;
    let rows = ny * nz;
    // the runs `[x0, x1)` of each row, rows in order (`first[r]..first[r + 1]`)
    let (mut runs, mut first) = (Vec::<(u32, u32)>::new(), Vec::with_capacity(rows + 1));
    for r in 0..rows {
        first.push(runs.len());
        let row = &mask[r * nx..(r + 1) * nx];
        let mut i = 0;
        while i < nx {
            if !row[i] {
                i += 1;
                continue;
            }
            let start = i;
            while i < nx && row[i] {
                i += 1;
            }
            runs.push((start as u32, i as u32));
        }
    }
    first.push(runs.len());
    let mut parent: Vec<u32> = (0..runs.len() as u32).collect();
    let join = |parent: &mut Vec<u32>, a: usize, b: usize| {
        let (ra, rb) = (find(parent, a as u32), find(parent, b as u32));
        // the earlier run is the root: a component's root is its first run
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
    };
    for r in 0..rows {
        let (j, k) = (r % ny, r / ny);
        let before = [(j > 0).then(|| r - 1), (k > 0).then(|| r - ny)];
        for q in before.into_iter().flatten() {
            let (mut a, mut b) = (first[r], first[q]);
            while a < first[r + 1] && b < first[q + 1] {
                let (ra, rb) = (runs[a], runs[b]);
                if ra.0 < rb.1 && rb.0 < ra.1 {
                    join(&mut parent, a, b);
                }
                if ra.1 < rb.1 {
                    a += 1;
                } else {
                    b += 1;
                }
            }
        }
    }
    let mut label = vec![0u32; mask.len()];
    let mut id = vec![0u32; runs.len()];
    let mut count = 0u32;
    for r in 0..rows {
        for a in first[r]..first[r + 1] {
            let root = find(&mut parent, a as u32) as usize;
            if id[root] == 0 {
                count += 1;
                id[root] = count;
            }
            let (x0, x1) = runs[a];
            label[r * nx + x0 as usize..r * nx + x1 as usize].fill(id[root]);
        }
    }
    (label, count as usize)
}

/// The root of `x` in the union–find forest `parent` (with path halving).
fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let up = parent[parent[x as usize] as usize];
        parent[x as usize] = up;
        x = up;
    }
    x
}

/// Sample counts of labels `0..=count`.
pub fn label_sizes(labels: &[u32], count: usize) -> Vec<usize> {
    let mut sizes = vec![0; count + 1];
    for &l in labels {
        sizes[l as usize] += 1;
    }
    sizes
}

/// `mask` without its components of fewer than `min_size` samples, and with its
/// holes (background components that do not touch the grid's border) filled where
/// they have fewer than `min_size` samples or fewer than `hole_fraction` of the
/// samples of the object around them (a dark figure on a coin, a nucleolus).
pub fn clean_mask(mask: &[bool], dims: Dims, min_size: usize, hole_fraction: f64) -> Vec<bool> {
    let (fg, nf) = components(mask, dims);
    let sizes = label_sizes(&fg, nf);
    let kept: Vec<bool> = fg.iter().map(|&l| l != 0 && sizes[l as usize] >= min_size).collect();
    let inverse: Vec<bool> = kept.iter().map(|&m| !m).collect();
    let (bg, nb) = components(&inverse, dims);
    let bg_sizes = label_sizes(&bg, nb);
    // the components that touch the grid's border (a hole does not)
    let [nx, ny, nz] = dims;
    let mut touches = vec![false; nb + 1];
    for k in 0..nz {
        for j in 0..ny {
            let row = &bg[nx * (j + ny * k)..nx * (j + ny * k + 1)];
            if j == 0 || j + 1 == ny || (nz > 1 && (k == 0 || k + 1 == nz)) {
                row.iter().for_each(|&l| touches[l as usize] = true);
            } else {
                touches[row[0] as usize] = true;
                touches[row[nx - 1] as usize] = true;
            }
        }
    }
    // the object around each hole: the component of a sample next to it
    let mut around = vec![0u32; nb + 1];
    let mut nb_samples = Vec::with_capacity(6);
    for (p, &l) in bg.iter().enumerate() {
        if l == 0 || touches[l as usize] || around[l as usize] != 0 {
            continue;
        }
        neighbours(dims, p, &mut nb_samples);
        if let Some(&q) = nb_samples.iter().find(|&&q| kept[q]) {
            around[l as usize] = fg[q];
        }
    }
    let fill: Vec<bool> = (0..=nb)
        .map(|l| {
            let size = bg_sizes[l] as f64;
            l != 0 && !touches[l] && (size < min_size as f64 || size < hole_fraction * sizes[around[l] as usize] as f64)
        })
        .collect();
    bg.iter().zip(&kept).map(|(&l, &m)| m || fill[l as usize]).collect()
}

/// A mask of the discs `(centre x, centre y, radius)` on a `w × h` grid.
#[cfg(test)]
fn disc_mask(w: usize, h: usize, discs: &[(f64, f64, f64)]) -> Vec<bool> {
    (0..w * h)
        .map(|p| {
            let (x, y) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
            discs.iter().any(|&(cx, cy, r)| (x - cx).hypot(y - cy) < r)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Labels by a flood fill over face neighbours, numbered in the order of each
    /// component's first sample.
    fn flood_fill(mask: &[bool], dims: Dims) -> (Vec<u32>, usize) {
        let mut label = vec![0u32; mask.len()];
        let (mut count, mut stack, mut nb) = (0u32, Vec::new(), Vec::new());
        for start in 0..mask.len() {
            if mask[start] && label[start] == 0 {
                count += 1;
                label[start] = count;
                stack.push(start);
                while let Some(p) = stack.pop() {
                    neighbours(dims, p, &mut nb);
                    for &q in &nb {
                        if mask[q] && label[q] == 0 {
                            label[q] = count;
                            stack.push(q);
                        }
                    }
                }
            }
        }
        (label, count as usize)
    }

    /// Random masks of several densities in 2D and 3D (spirals, combs and single
    /// samples among them): the same labels, in the same order, as a flood fill.
    #[test]
    fn components_match_a_flood_fill() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for dims in [[1, 1, 1], [7, 1, 1], [1, 9, 1], [23, 17, 1], [64, 48, 1], [9, 8, 7], [16, 5, 12]] {
            for density in [0.1, 0.4, 0.55, 0.7, 0.95] {
                let n = dims[0] * dims[1] * dims[2];
                let mask: Vec<bool> = (0..n).map(|_| (next() % 1000) as f64 / 1000.0 < density).collect();
                assert_eq!(components(&mask, dims), flood_fill(&mask, dims), "{dims:?} at {density}");
            }
        }
    }

    #[test]
    fn specks_go_and_small_holes_are_filled() {
        let (w, h) = (30, 30);
        let mut m = disc_mask(w, h, &[(15.0, 15.0, 10.0)]);
        m[15 + w * 15] = false; // a one-pixel hole
        m[2 + w * 2] = true; // a speck
        let c = clean_mask(&m, [w, h, 1], 5, 0.0);
        assert!(c[15 + w * 15] && !c[2 + w * 2]);
        // a hole of 21 samples in a disc of about 300: kept below a tenth, filled below a quarter
        let ring: Vec<bool> = (0..w * h)
            .map(|p| {
                let r = ((p % w) as f64 + 0.5 - 15.0).hypot((p / w) as f64 + 0.5 - 15.0);
                (2.6..10.0).contains(&r)
            })
            .collect();
        assert!(!clean_mask(&ring, [w, h, 1], 5, 0.05)[15 + w * 15]);
        assert!(clean_mask(&ring, [w, h, 1], 5, 0.25)[15 + w * 15]);
    }
}
