//! Binary masks and label images on a grid (`x` fastest, as [`super::Grid`]):
//! connected components, hole filling, the Euclidean distance transform and the
//! split of touching objects by a persistence watershed on it. Face neighbours
//! (4 in 2D, 6 in 3D) throughout. Labels are `1..=count`, 0 is background.

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

/// The 1D squared distance transform of sampled function `f` with sample spacing
/// `h` (Felzenszwalb–Huttenlocher): `d(q) = min_p (h²(q − p)² + f(p))`.
fn squared_distance_1d(f: &[f64], h: f64, d: &mut [f64], v: &mut Vec<usize>, z: &mut Vec<f64>) {
    let n = f.len();
    v.clear();
    z.clear();
    let h2 = h * h;
    let inter = |p: usize, q: usize| {
        ((f[q] / h2 + (q * q) as f64) - (f[p] / h2 + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
    };
    for q in 0..n {
        if f[q] == f64::INFINITY {
            continue;
        }
        loop {
            match v.last() {
                Some(&p) if inter(p, q) <= *z.last().unwrap() => {
                    v.pop();
                    z.pop();
                }
                Some(&p) => {
                    z.push(inter(p, q));
                    break;
                }
                None => {
                    z.push(f64::NEG_INFINITY);
                    break;
                }
            }
        }
        v.push(q);
    }
    if v.is_empty() {
        d.iter_mut().for_each(|x| *x = f64::INFINITY);
        return;
    }
    z.push(f64::INFINITY);
    let mut k = 0;
    for (q, dq) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        *dq = h2 * (q as f64 - p as f64).powi(2) + f[p];
    }
}

/// [`squared_distance_1d`] of a line of zeros and infinities, in place (the
/// same values): two sweeps, the number of steps to the nearest zero on the
/// left, then on either side.
fn squared_distance_to_zeros(line: &mut [f64], h: f64) {
    let mut steps = f64::INFINITY;
    for x in line.iter_mut() {
        steps = if *x == 0.0 { 0.0 } else { steps + 1.0 };
        *x = steps;
    }
    let (h2, mut steps) = (h * h, f64::INFINITY);
    for x in line.iter_mut().rev() {
        steps = if *x == 0.0 { 0.0 } else { steps + 1.0 };
        let k = x.min(steps);
        *x = h2 * (k * k);
    }
}

/// Euclidean distance from each sample of `mask` to the nearest sample outside it
/// (0 outside), with sample spacings `spacing` per axis; samples beyond the grid
/// count as outside.
pub fn distance_transform(mask: &[bool], dims: Dims, spacing: [f64; 3]) -> Vec<f64> {
    // pad by one background sample on every side of the used axes
    let used: Vec<usize> = (0..3).filter(|&a| dims[a] > 1 || a < 2).collect();
    let pd: Dims = std::array::from_fn(|a| if used.contains(&a) { dims[a] + 2 } else { dims[a] });
    let off = |a: usize| used.contains(&a) as usize;
    let total = pd[0] * pd[1] * pd[2];
    let mut g = vec![0.0; total];
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                if mask[i + dims[0] * (j + dims[1] * k)] {
                    g[(i + off(0)) + pd[0] * ((j + off(1)) + pd[1] * (k + off(2)))] = f64::INFINITY;
                }
            }
        }
    }
    let (mut v, mut z) = (Vec::new(), Vec::new());
    // lines along `a` start at `low + n·stride·high` (`low < stride`); they are
    // taken `BLOCK` neighbouring lines at a time, so that every read and write
    // uses whole cache lines
    const BLOCK: usize = 8;
    for &a in &used {
        let n = pd[a];
        let stride: usize = pd[..a].iter().product();
        let (mut lines, mut out) = (vec![0.0; BLOCK * n], vec![0.0; n]);
        for high in 0..total / (n * stride) {
            for low in (0..stride).step_by(BLOCK) {
                let width = BLOCK.min(stride - low);
                let base = low + n * stride * high;
                for t in 0..n {
                    let row = &g[base + t * stride..base + t * stride + width];
                    for (b, &x) in row.iter().enumerate() {
                        lines[b * n + t] = x;
                    }
                }
                for b in 0..width {
                    let line = &mut lines[b * n..(b + 1) * n];
                    if a == used[0] {
                        // the first pass sees only 0 and ∞: the distance to the nearest 0
                        squared_distance_to_zeros(line, spacing[a]);
                    } else if line.iter().any(|&x| x > 0.0) {
                        squared_distance_1d(line, spacing[a], &mut out, &mut v, &mut z);
                        line.copy_from_slice(&out);
                    }
                }
                for t in 0..n {
                    let row = &mut g[base + t * stride..base + t * stride + width];
                    for (b, x) in row.iter_mut().enumerate() {
                        *x = lines[b * n + t];
                    }
                }
            }
        }
    }
    let mut d = vec![0.0; mask.len()];
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                d[i + dims[0] * (j + dims[1] * k)] =
                    g[(i + off(0)) + pd[0] * ((j + off(1)) + pd[1] * (k + off(2)))].sqrt();
            }
        }
    }
    d
}

/// Split the objects of `mask` where they touch: a watershed of the distance
/// transform `d` (descending flood from its maxima) whose basins are merged across
/// a saddle unless both their peaks rise above it by at least
/// `max(depth, relative_depth · lower peak)` (a persistence criterion: two discs
/// joined by a neck stay two objects when the neck is clearly narrower than both).
/// Returns labels `1..=count` (0 outside `mask`) and `count`.
pub fn split_touching(mask: &[bool], d: &[f64], dims: Dims, depth: f64, relative_depth: f64) -> (Vec<u32>, usize) {
    let mut order: Vec<usize> = (0..mask.len()).filter(|&p| mask[p]).collect();
    order.sort_unstable_by(|&a, &b| d[b].total_cmp(&d[a]).then(a.cmp(&b)));
    const NONE: u32 = u32::MAX;
    let mut basin = vec![NONE; mask.len()];
    let mut parent: Vec<u32> = Vec::new();
    let mut peak: Vec<f64> = Vec::new();
    let mut nb = Vec::with_capacity(6);
    let mut roots: Vec<u32> = Vec::with_capacity(6);
    for &p in &order {
        neighbours(dims, p, &mut nb);
        roots.clear();
        for &q in &nb {
            if basin[q] != NONE {
                let r = find(&mut parent, basin[q]);
                if !roots.contains(&r) {
                    roots.push(r);
                }
            }
        }
        if roots.is_empty() {
            parent.push(parent.len() as u32);
            peak.push(d[p]);
            basin[p] = (parent.len() - 1) as u32;
            continue;
        }
        // highest peak first; merge every basin that does not stand out of this saddle
        roots.sort_unstable_by(|&a, &b| peak[b as usize].total_cmp(&peak[a as usize]));
        let main = roots[0];
        for &r in &roots[1..] {
            let low = peak[r as usize];
            if low - d[p] < depth.max(relative_depth * low) {
                parent[r as usize] = main;
            }
        }
        basin[p] = main;
    }
    // compact labels
    let mut id = vec![0u32; parent.len()];
    let mut count = 0u32;
    let mut labels = vec![0u32; mask.len()];
    for &p in &order {
        let r = find(&mut parent, basin[p]) as usize;
        if id[r] == 0 {
            count += 1;
            id[r] = count;
        }
        labels[p] = id[r];
    }
    (labels, count as usize)
}

/// Background samples between touching objects: every sample adjacent to a sample
/// of a smaller label loses its label, so that the objects of `labels` are
/// separated by at least one sample. Returns the samples cleared.
pub fn separate(labels: &mut [u32], dims: Dims) -> Vec<usize> {
    let mut cleared = Vec::new();
    let mut nb = Vec::with_capacity(6);
    for p in 0..labels.len() {
        let l = labels[p];
        if l == 0 {
            continue;
        }
        neighbours(dims, p, &mut nb);
        if nb.iter().any(|&q| labels[q] != 0 && labels[q] < l) {
            cleared.push(p);
        }
    }
    for &p in &cleared {
        labels[p] = 0;
    }
    cleared
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc_mask(w: usize, h: usize, discs: &[(f64, f64, f64)]) -> Vec<bool> {
        (0..w * h)
            .map(|p| {
                let (x, y) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
                discs.iter().any(|&(cx, cy, r)| (x - cx).hypot(y - cy) < r)
            })
            .collect()
    }

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

    /// In 3D with anisotropic spacing, on a grid whose lines do not fill whole
    /// blocks: the exact distance to the nearest sample outside.
    #[test]
    fn distance_transform_in_3d_matches_the_brute_force() {
        let dims = [11, 10, 9];
        let spacing = [1.0, 1.5, 2.0];
        let at = |p: usize| [(p % 11) as isize, ((p / 11) % 10) as isize, (p / 110) as isize];
        let mask: Vec<bool> = (0..990)
            .map(|p| {
                let [i, j, k] = at(p).map(|c| c as f64);
                (i - 5.0).powi(2) / 16.0 + (j - 4.5).powi(2) / 12.0 + (k - 4.0).powi(2) / 9.0 < 1.0
                    || (i, j) == (2.0, 7.0)
            })
            .collect();
        let d = distance_transform(&mask, dims, spacing);
        for p in 0..990 {
            let mut want: f64 = 0.0;
            if mask[p] {
                want = f64::INFINITY;
                let c = at(p);
                for x in -1..=11isize {
                    for y in -1..=10isize {
                        for z in -1..=9isize {
                            let inside = (0..11).contains(&x) && (0..10).contains(&y) && (0..9).contains(&z);
                            if !inside || !mask[x as usize + 11 * (y as usize + 10 * z as usize)] {
                                let r = [x - c[0], y - c[1], z - c[2]];
                                let d2: f64 = (0..3).map(|a| (r[a] as f64 * spacing[a]).powi(2)).sum();
                                want = want.min(d2.sqrt());
                            }
                        }
                    }
                }
            }
            assert!((d[p] - want).abs() < 1e-12, "sample {p}: {} against {want}", d[p]);
        }
    }

    #[test]
    fn distance_transform_matches_the_brute_force() {
        let (w, h) = (40, 30);
        let m = disc_mask(w, h, &[(15.0, 14.0, 9.0), (28.0, 16.0, 7.0)]);
        let d = distance_transform(&m, [w, h, 1], [1.0, 1.0, 1.0]);
        for p in 0..w * h {
            let want = if !m[p] {
                0.0
            } else {
                let (i, j) = ((p % w) as isize, (p / w) as isize);
                let mut best = f64::INFINITY;
                for y in -1..=h as isize {
                    for x in -1..=w as isize {
                        let outside =
                            x < 0 || y < 0 || x >= w as isize || y >= h as isize || !m[x as usize + w * y as usize];
                        if outside {
                            best = best.min(((x - i) as f64).hypot((y - j) as f64));
                        }
                    }
                }
                best
            };
            assert!((d[p] - want).abs() < 1e-9, "{p}: {} {want}", d[p]);
        }
    }

    #[test]
    fn two_touching_discs_are_split_and_one_disc_is_not() {
        let (w, h) = (80, 40);
        let dims = [w, h, 1];
        let m = disc_mask(w, h, &[(25.0, 20.0, 12.0), (46.0, 20.0, 11.0)]);
        let d = distance_transform(&m, dims, [1.0; 3]);
        let (mut labels, n) = split_touching(&m, &d, dims, 2.0, 0.25);
        assert_eq!(n, 2);
        assert_eq!(components(&m, dims).1, 1);
        let cleared = separate(&mut labels, dims);
        assert!(!cleared.is_empty());
        let sep: Vec<bool> = labels.iter().map(|&l| l != 0).collect();
        assert_eq!(components(&sep, dims).1, 2);
        // an ellipse of aspect 2 stays one object
        let e: Vec<bool> = (0..w * h)
            .map(|p| {
                let (x, y) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
                ((x - 40.0) / 24.0).powi(2) + ((y - 20.0) / 12.0).powi(2) < 1.0
            })
            .collect();
        let d = distance_transform(&e, dims, [1.0; 3]);
        assert_eq!(split_touching(&e, &d, dims, 2.0, 0.25).1, 1);
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
                r < 10.0 && r >= 2.6
            })
            .collect();
        assert!(!clean_mask(&ring, [w, h, 1], 5, 0.05)[15 + w * 15]);
        assert!(clean_mask(&ring, [w, h, 1], 5, 0.25)[15 + w * 15]);
    }
}
