//! Segments shorter than a length collapsed to their midpoints (a loop held
//! beside a contact, which no other management may touch).

use super::Loop;
use crate::geometry::Point;

impl Loop {
    /// The loop with every segment shorter than `min` collapsed to its midpoint
    /// (at least three vertices kept), or `None` if it has none.
    pub(in crate::geometry) fn collapse_short(&self, min: f64) -> Option<Loop> {
        let l = self;
        let n = l.p.len();
        let next = |k: usize| if k + 1 == n { l.p[0] + l.shift } else { l.p[k + 1] };
        if n <= 3 || (0..n).all(|k| (next(k) - l.p[k]).norm() >= min) {
            return None;
        }
        let mut p: Vec<Point<2>> = Vec::with_capacity(n);
        for &x in &l.p {
            match p.last_mut() {
                Some(last) if (x - *last).norm() < min => *last = 0.5 * (*last + x),
                _ => p.push(x),
            }
        }
        // the closing segment (a periodic loop's last point lies one shift before the first)
        while p.len() > 3 && (p[0] + l.shift - p[p.len() - 1]).norm() < min {
            let last = p.pop().expect("more than three points");
            p[0] = 0.5 * (p[0] + last - l.shift);
        }
        (p.len() >= 3 && p.len() < n).then_some(Loop { p, shift: l.shift })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Short segments collapse to their midpoints, the closing one too (across a
    /// periodic loop's shift); a loop with none, or of three points, is left alone.
    #[test]
    fn short_segments_collapse_to_their_midpoints() {
        let p = |x: f64, y: f64| Point::<2>::new(x, y);
        let square = Loop {
            p: vec![p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1e-3), p(1.0, 1.0), p(0.0, 1.0)],
            shift: Point::<2>::zeros(),
        };
        let c = square.collapse_short(0.01).unwrap();
        assert_eq!(c.p, vec![p(0.0, 0.0), p(1.0, 0.5e-3), p(1.0, 1.0), p(0.0, 1.0)]);
        assert!(c.collapse_short(0.01).is_none());
        // the closing segment, from the last point to the first
        let closing = Loop {
            p: vec![p(1e-3, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0), p(0.0, 0.0)],
            shift: Point::<2>::zeros(),
        };
        let c = closing.collapse_short(0.01).unwrap();
        assert_eq!(c.p, vec![p(0.5e-3, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]);
        // a periodic chain: its last point lies one shift before the first
        let shift = p(2.0, 0.0);
        let chain = Loop { p: vec![p(0.0, 0.0), p(1.0, 1.0), p(2.0 - 1e-3, 0.0)], shift };
        assert!(chain.collapse_short(0.01).is_none(), "three points are kept");
        let chain = Loop { p: vec![p(0.0, 0.0), p(0.5, 1.0), p(1.5, 1.0), p(2.0 - 1e-3, 0.0)], shift };
        let c = chain.collapse_short(0.01).unwrap();
        assert_eq!(c.p.len(), 3);
        assert!((c.p[0] - p(-0.5e-3, 0.0)).norm() < 1e-15, "{:?}", c.p[0]);
    }
}
