//! The area-preserving regularization sweep of one loop: red–black Gauss–Seidel
//! moves along the chords towards the desired sizes, vertices of one colour at a
//! time so that the sweep runs as a vector loop.

use super::Loop;
use crate::geometry::Point;

/// `sweeps` red–black Gauss–Seidel sweeps on one loop towards the desired sizes
/// `hd`: vertex `k` moves along the chord `c = X_{k+1} − X_{k−1}` to
/// `X_{k−1} + λ_k c`, `λ_k = (h_{k−1} + h_k)/(h_{k−1} + 2h_k + h_{k+1})` (the point
/// splitting the chord in the ratio of the sizes around it), i.e. by
/// `((X_{k−1} + λ_k c − X_k)·c / |c|²) c`. The enclosed area is linear in each single
/// vertex with the others fixed and its gradient `½ J c` is normal to the chord, so
/// every move keeps the area exactly (up to round-off).
///
/// With `bounds = Some((lo, hi))` the target point is moved, where the chord allows,
/// so that both segments at `k` end up inside `[lo, hi]` (the midpoint where it does
/// not): sizes only set ratios, and one sweep per step cannot carry length along a
/// long curve, so without this a stretch of segments longer than the sizes piles up
/// against `h_max` and is split a segment at a time, a new connectivity each time.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(crate) fn regularize_loop(l: &mut Loop, hd: &[f64], sweeps: usize, bounds: Option<(f64, f64)>) {
    let n = l.len();
    if n < 3 || sweeps == 0 {
        return;
    }
    let (lo, hi) = bounds.unwrap_or((0.0, f64::INFINITY));
    let mut c = Coloured::split(&l.p, hd);
    let shift = l.shift;
    // red–black order: the moves of one colour do not depend on each other (nor
    // interact in the area); each colour is a slice of its own, so that its moves
    // run as a vector loop. The first vertex and the last close the loop and go
    // alone (with n odd the last is red, a neighbour of the first, and goes after
    // the black ones).
    let (reds, blacks) = (n / 2, (n - 1) / 2);
    let last_is_red = n % 2 == 1;
    for _ in 0..sweeps {
        let before_first = if last_is_red { c.red[reds] } else { c.black[blacks] } - shift;
        let moved = relaxed(before_first, c.red[0], c.black[0], c.red_lambda[0], lo, hi);
        c.red[0] = moved;
        let Coloured { red, black, red_lambda, black_lambda, .. } = &mut c;
        relax_run(&mut red[1..reds], &black[..reds - 1], &black[1..reds], &red_lambda[1..reds], lo, hi);
        relax_run(&mut black[..blacks], &red[..blacks], &red[1..blacks + 1], &black_lambda[..blacks], lo, hi);
        let after_last = red[0] + shift;
        if last_is_red {
            red[reds] = relaxed(black[blacks - 1], red[reds], after_last, red_lambda[reds], lo, hi);
        } else {
            black[blacks] = relaxed(red[reds - 1], black[blacks], after_last, black_lambda[blacks], lo, hi);
        }
    }
    c.merge(&mut l.p);
}

/// A loop's vertices (and the ratios `λ` of [`regularize_loop`]) split by the
/// parity of their index: `red[i]` is vertex `2i`, `black[i]` vertex `2i + 1`.
struct Coloured {
    red: Vec<Point<2>>,
    black: Vec<Point<2>>,
    red_lambda: Vec<f64>,
    black_lambda: Vec<f64>,
}

impl Coloured {
    #[inline(always)]
    fn split(p: &[Point<2>], hd: &[f64]) -> Coloured {
        let n = p.len();
        let ratio = |hp: f64, hi: f64, hn: f64| (hp + hi) / (hp + 2.0 * hi + hn);
        let mut lambda = vec![0.0; n];
        lambda[0] = ratio(hd[n - 1], hd[0], hd[1]);
        lambda[n - 1] = ratio(hd[n - 2], hd[n - 1], hd[0]);
        for (((lam, &hp), &hi), &hn) in lambda[1..n - 1].iter_mut().zip(&hd[..n - 2]).zip(&hd[1..n - 1]).zip(&hd[2..]) {
            *lam = ratio(hp, hi, hn);
        }
        let (reds, blacks) = (n.div_ceil(2), n / 2);
        let (mut red, mut black) = (vec![Point::<2>::zeros(); reds], vec![Point::<2>::zeros(); blacks]);
        let (mut red_lambda, mut black_lambda) = (vec![0.0; reds], vec![0.0; blacks]);
        for (((r, b), x), ((rl, bl), lam)) in red
            .iter_mut()
            .zip(&mut black)
            .zip(p.chunks_exact(2))
            .zip(red_lambda.iter_mut().zip(&mut black_lambda).zip(lambda.chunks_exact(2)))
        {
            (*r, *b, *rl, *bl) = (x[0], x[1], lam[0], lam[1]);
        }
        if n % 2 == 1 {
            red[reds - 1] = p[n - 1];
            red_lambda[reds - 1] = lambda[n - 1];
        }
        Coloured { red, black, red_lambda, black_lambda }
    }

    #[inline(always)]
    fn merge(&self, p: &mut [Point<2>]) {
        let n = p.len();
        for ((x, &r), &b) in p.chunks_exact_mut(2).zip(&self.red).zip(&self.black) {
            (x[0], x[1]) = (r, b);
        }
        if n % 2 == 1 {
            p[n - 1] = self.red[n / 2];
        }
    }
}

/// [`relaxed`] for every vertex `x[i]` of one colour between `prev[i]` and `next[i]`.
#[inline(always)]
fn relax_run(x: &mut [Point<2>], prev: &[Point<2>], next: &[Point<2>], lambda: &[f64], lo: f64, hi: f64) {
    for (((x, &prev), &next), &lam) in x.iter_mut().zip(prev).zip(next).zip(lambda) {
        *x = relaxed(prev, *x, next, lam, lo, hi);
    }
}

/// Where [`regularize_loop`] moves `x` between `prev` and `next`: along the chord
/// `c = next − prev` to the foot of the point `λ'` of the way along it, `λ'` the
/// ratio `λ` clamped so that `λ'|c|` and `(1 − λ')|c|` lie in `[lo, hi]` (½ where no
/// ratio does). Written without branches (plain comparisons, which select), so that
/// consecutive vertices of a colour overlap in the pipeline: the move is
/// `x + (λ' + (prev − x)·c/|c|²) c`, none if `c = 0`.
#[inline(always)]
fn relaxed(prev: Point<2>, x: Point<2>, next: Point<2>, lambda: f64, lo: f64, hi: f64) -> Point<2> {
    let (cx, cy) = (next.x - prev.x, next.y - prev.y);
    let cc = cx * cx + cy * cy;
    let cl = cc.sqrt();
    let inv = 1.0 / cl;
    let lower = cl - hi;
    let upper = cl - lo;
    let a = if lower > lo { lower } else { lo } * inv;
    let b = if upper < hi { upper } else { hi } * inv;
    let above = if lambda > a { lambda } else { a };
    let clamped = if above < b { above } else { b };
    let lam = if a <= b { clamped } else { 0.5 };
    let alpha = ((prev.x + lam * cx - x.x) * cx + (prev.y + lam * cy - x.y) * cy) / cc;
    if cc > 0.0 {
        Point::<2>::new(x.x + alpha * cx, x.y + alpha * cy)
    } else {
        x
    }
}
