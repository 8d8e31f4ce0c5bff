//! Contact of a curve with itself across its interior, below the mesh resolution.
//!
//! Topological changes are triggered by crossings ([`super::resolve_crossings`]). A
//! gradient flow can instead bring two parts of a curve together and hold them at a
//! gap of a fraction of a segment, which the mesh cannot resolve (the stressed film:
//! two mushroom caps closing over a channel). [`close_contact`] treats such a gap as
//! contact: the closest pair of vertices `x_i`, `x_j` that face each other across
//! the interior (the left side of the curve) with
//!
//! `|x_j − x_i| < fraction · min(h_i, h_j)`,
//!
//! `h` the shorter adjacent segment, and at least four vertices apart along the
//! curve, is pushed past each other so that their segments cross, ready for the
//! crossing resolution.

use super::{CurveMesh, Point};

/// Vertices this close along the same component never count as a contact.
const MIN_SEPARATION: usize = 4;

/// The curve with its closest contact (see the module documentation) made into a
/// crossing, or `None` when there is none.
pub fn close_contact(mesh: &CurveMesh, fraction: f64) -> Option<CurveMesh> {
    let x = mesh.positions();
    let period = mesh.period();
    let wrap = |d: Point<2>| match period {
        Some(l) => Point::<2>::new(d.x - l * (d.x / l).round(), d.y),
        None => d,
    };
    // per vertex: component, position along it, shorter adjacent segment, left normal
    let n = x.len();
    let (mut comp, mut pos, mut h, mut left) =
        (vec![usize::MAX; n], vec![0; n], vec![0.0; n], vec![Point::<2>::zeros(); n]);
    let cycles = mesh.cycles();
    for (c, cycle) in cycles.iter().enumerate() {
        let m = cycle.len();
        for (k, &v) in cycle.iter().enumerate() {
            let (prev, next) = (cycle[(k + m - 1) % m], cycle[(k + 1) % m]);
            let (a, b) = (wrap(x[v] - x[prev]), wrap(x[next] - x[v]));
            comp[v] = c;
            pos[v] = k;
            h[v] = a.norm().min(b.norm());
            let t = a + b;
            left[v] = Point::<2>::new(-t.y, t.x);
        }
    }
    let mut best: Option<(f64, usize, usize)> = None;
    for i in 0..n {
        if comp[i] == usize::MAX {
            continue;
        }
        for j in i + 1..n {
            if comp[j] == usize::MAX {
                continue;
            }
            if comp[i] == comp[j] {
                let m = cycles[comp[i]].len();
                let k = pos[i].abs_diff(pos[j]);
                if k.min(m - k) < MIN_SEPARATION {
                    continue;
                }
            }
            let d = wrap(x[j] - x[i]);
            let dist = d.norm();
            if dist >= fraction * h[i].min(h[j]) || best.is_some_and(|b| b.0 <= dist) {
                continue;
            }
            // facing each other across the interior
            if left[i].dot(&d) > 0.0 && left[j].dot(&d) < 0.0 {
                best = Some((dist, i, j));
            }
        }
    }
    let (_, i, j) = best?;
    // both to the midpoint, then a quarter of the shorter segment past each other
    let d = wrap(x[j] - x[i]);
    let mid = x[i] + 0.5 * d;
    let push = 0.25 * h[i].min(h[j]) * d.normalize();
    let mut moved = x.to_vec();
    moved[i] = mid + push;
    moved[j] = mid - push;
    Some(mesh.with_positions(moved))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{polygon, resolve_intersections};

    /// A dumbbell whose neck is narrower than a fraction of its segments pinches into
    /// two lobes; a wide neck does not.
    #[test]
    fn a_neck_below_the_resolution_pinches() {
        let dumbbell = |gap: f64| -> CurveMesh {
            // counter-clockwise outline: two 1×1 squares joined by a neck of width `gap`
            let g = 0.5 * gap;
            let pts: Vec<Point<2>> = [
                [-1.0, -0.5],
                [-0.1, -0.5],
                [0.0, -g],
                [0.1, -0.5],
                [1.0, -0.5],
                [1.0, 0.5],
                [0.1, 0.5],
                [0.0, g],
                [-0.1, 0.5],
                [-1.0, 0.5],
            ]
            .iter()
            .map(|p| Point::<2>::new(p[0], p[1]))
            .collect();
            polygon(&pts, Some(80)).unwrap()
        };
        let wide = dumbbell(0.3);
        assert!(close_contact(&wide, 0.5).is_none());
        let narrow = dumbbell(0.01);
        let touched = close_contact(&narrow, 0.5).expect("a contact");
        let split = resolve_intersections(&touched, 1e-6, false).unwrap().expect("a crossing");
        assert_eq!(split.num_components(), 2);
        let areas = split.component_measures();
        assert!(areas.iter().all(|a| (a - 0.95).abs() < 0.05), "{areas:?}");
    }
}
