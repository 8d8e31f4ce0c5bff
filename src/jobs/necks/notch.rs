//! The notch test of a cut through a surface's object: whether the cut between
//! two parts is a neck all around its rim (two touching objects) or the floor of
//! a deep inlet into one (see [`notched`]).

/// Least mean fraction of a ball around the rim of a cut that lies inside the
/// object: more than a flat boundary's half. The rim of a neck between two balls
/// is a notch, but a ball of the neck's radius reaches past where their surfaces
/// curve away, so that its fraction is lower than a disc's in 2D ([`super::PINCH`]):
/// on the generated touching pairs' necks (BENCHMARKS.md) 0.53–0.56, and 0.38–0.44
/// for cuts through the convex side of a ball.
const PINCH_3D: f64 = 0.5;

/// The six face neighbours of sample `p` on a grid of `dims`.
fn faces(dims: [usize; 3], p: usize) -> impl Iterator<Item = usize> {
    let (i, j, k) = (p % dims[0], (p / dims[0]) % dims[1], p / (dims[0] * dims[1]));
    let (sx, sy) = (1, dims[0]);
    let sz = dims[0] * dims[1];
    [
        (i > 0).then(|| p - sx),
        (i + 1 < dims[0]).then(|| p + sx),
        (j > 0).then(|| p - sy),
        (j + 1 < dims[1]).then(|| p + sy),
        (k > 0).then(|| p - sz),
        (k + 1 < dims[2]).then(|| p + sz),
    ]
    .into_iter()
    .flatten()
}

/// Whether the cut between parts `a` and `b` of `labels` (a window of `dims`
/// samples from `start` in an image of `image` samples, with the object's
/// distance transform `dist`) is a notch all around its rim, and the cut's widest
/// sample (`None` where the parts do not touch, which counts as a notch). The
/// rim is the cut's samples next to the background; around each, a ball of the
/// neck's radius (the cut's widest distance, at least 2) lies in the object by
/// more than [`PINCH_3D`] on average (a flat boundary fills half of it, plus
/// `3/(8r)` for the rim sample half a sample inside it, which is taken off). A
/// rim sample within that radius of the image's faces counts as a notch (the
/// object goes on beyond them). As for curves, this tells a neck between two
/// touching objects from a cut below a deep inlet into one object.
pub(super) fn notched(
    labels: &[u32],
    dist: &[f64],
    dims: [usize; 3],
    start: [usize; 3],
    image: [usize; 3],
    a: u32,
    b: u32,
) -> (bool, Option<usize>) {
    let cut: Vec<usize> =
        (0..labels.len()).filter(|&p| labels[p] == a && faces(dims, p).any(|q| labels[q] == b)).collect();
    let Some(&widest) = cut.iter().max_by(|&&p, &&q| dist[p].total_cmp(&dist[q])) else {
        return (true, None);
    };
    let rim: Vec<usize> = cut.iter().copied().filter(|&p| faces(dims, p).any(|q| labels[q] == 0)).collect();
    if rim.is_empty() {
        return (true, Some(widest));
    }
    let r = dist[widest].max(2.0);
    let reach = r.ceil() as i64;
    let mut sum = 0.0;
    for &p in &rim {
        let at = [p % dims[0], (p / dims[0]) % dims[1], p / (dims[0] * dims[1])];
        let (mut inside, mut all) = (0usize, 0usize);
        let mut at_edge = false;
        'ball: for dk in -reach..=reach {
            for dj in -reach..=reach {
                for di in -reach..=reach {
                    if ((di * di + dj * dj + dk * dk) as f64) > r * r {
                        continue;
                    }
                    let q = [at[0] as i64 + di, at[1] as i64 + dj, at[2] as i64 + dk];
                    if (0..3).any(|c| q[c] + (start[c] as i64) < 0 || q[c] + start[c] as i64 >= image[c] as i64) {
                        at_edge = true;
                        break 'ball;
                    }
                    all += 1;
                    // beyond the window (a sample around the object's box) is background
                    if (0..3).all(|c| q[c] >= 0 && (q[c] as usize) < dims[c]) {
                        let s = q[0] as usize + dims[0] * (q[1] as usize + dims[1] * q[2] as usize);
                        inside += usize::from(labels[s] != 0);
                    }
                }
            }
        }
        sum += if at_edge { 1.0 } else { inside as f64 / all as f64 - 3.0 / (8.0 * r) };
    }
    let fill = sum / rim.len() as f64;
    tracing::debug!(fill, rim = rim.len(), cut = cut.len(), radius = r, "the rim of a cut");
    (fill > PINCH_3D, Some(widest))
}
