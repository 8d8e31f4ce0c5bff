use super::*;

/// Every pair, tested directly.
fn brute_force(points: &[Point<2>], segments: &[[usize; 2]]) -> Vec<(usize, usize)> {
    let segs: Vec<Seg> = segments.iter().map(|s| Seg { p: points[s[0]], q: points[s[1]], id: *s }).collect();
    let mut out = Vec::new();
    for a in 0..segs.len() {
        for b in a + 1..segs.len() {
            if intersect_pair(&segs[a], &segs[b], a, b).is_some() {
                out.push((a, b));
            }
        }
    }
    out
}

/// A tiny deterministic generator (xorshift), uniform in [0, 1).
pub(in crate::geometry) fn rng(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// Closed polylines: wiggly circles with random radii, centres and sampling, some
/// crossing themselves (large wiggles) and each other, some with spikes that fold
/// back onto themselves, some with repeated points.
#[test]
fn runs_find_exactly_the_pairs_of_the_brute_force() {
    let mut state = 0x2545_F491_4F6C_DD1D_u64;
    let mut total_hits = 0;
    for case in 0..60 {
        let mut points = Vec::new();
        let mut segments = Vec::new();
        let components = 1 + (rng(&mut state) * 3.0) as usize;
        for _ in 0..components {
            let n = 8 + (rng(&mut state) * 300.0) as usize;
            let (cx, cy) = (rng(&mut state) * 2.0, rng(&mut state) * 2.0);
            let r = 0.3 + rng(&mut state);
            let wiggle = if case % 3 == 0 { 0.0 } else { rng(&mut state) * 0.6 };
            let k = 2.0 + (rng(&mut state) * 9.0).floor();
            let base = points.len();
            for j in 0..n {
                let t = 2.0 * std::f64::consts::PI * (j as f64 + 0.8 * rng(&mut state)) / n as f64;
                let rr = r * (1.0 + wiggle * (k * t).sin());
                let mut p = Point::<2>::new(cx + rr * t.cos(), cy + rr * t.sin());
                if case % 5 == 1 && j % 37 == 5 {
                    p = points[base + j - 2]; // a spike folding back
                }
                if case % 7 == 2 && j % 41 == 3 {
                    p = points[base + j - 1]; // a repeated point
                }
                points.push(p);
            }
            segments.extend((0..n).map(|j| [base + j, base + (j + 1) % n]));
        }
        let fast: Vec<(usize, usize)> =
            find_segment_intersections(&points, &segments).iter().map(|h| (h.a, h.b)).collect();
        let slow = brute_force(&points, &segments);
        assert_eq!(fast, slow, "case {case}");
        total_hits += slow.len();
    }
    assert!(total_hits > 100, "the cases cross: {total_hits}");
}

/// Many short segments in the cells of a few long ones (their mean sets the
/// cells): a comb of tiny teeth along a long edge and a tiny random walk that
/// crosses itself, on the refined grids of dense cells.
#[test]
fn dense_cells_find_exactly_the_pairs_of_the_brute_force() {
    let mut state = 0x9E37_79B9_7F4A_7C15_u64;
    for case in 0..4 {
        let mut points = vec![Point::<2>::new(0.0, 0.0), Point::<2>::new(100.0, 0.0), Point::<2>::new(100.0, 50.0)];
        // the comb, from (100, 50) back to (99, 50): 1,200 segments, teeth of height 0.01
        let teeth = 600;
        for j in 0..teeth {
            let x = 100.0 - (j as f64 + 0.5) / teeth as f64;
            let h = if case % 2 == 1 && j % 97 == 13 { -0.02 } else { 0.01 }; // some teeth cross
            points.push(Point::<2>::new(x + 0.0008, 50.0));
            points.push(Point::<2>::new(x, 50.0 + h));
        }
        // a random walk of tiny steps near (0, 25)
        let mut p = Point::<2>::new(0.5, 25.0);
        for _ in 0..(300 + 200 * case) {
            p += Point::<2>::new(rng(&mut state) - 0.5, rng(&mut state) - 0.5) * 0.004;
            points.push(p);
        }
        let n = points.len();
        let segments: Vec<[usize; 2]> = (0..n).map(|j| [j, (j + 1) % n]).collect();
        let grid = RunGrid::build(&points, &segments, None);
        let mut per_cell = std::collections::HashMap::new();
        for r in &grid.runs {
            *per_cell.entry(r.cell).or_insert(0) += (r.last - r.first + 1) as usize;
        }
        assert!(per_cell.values().filter(|&&m| m > DENSE).count() >= 2, "case {case}: dense cells");
        let fast: Vec<(usize, usize)> =
            find_segment_intersections(&points, &segments).iter().map(|h| (h.a, h.b)).collect();
        let slow = brute_force(&points, &segments);
        assert_eq!(fast, slow, "case {case}");
        assert!(!slow.is_empty() || case == 0, "case {case} crosses");
    }
}

#[test]
fn crossing_and_touching_pairs() {
    let pts = vec![
        Point::<2>::new(0.0, 0.0),
        Point::<2>::new(1.0, 1.0),
        Point::<2>::new(0.0, 1.0),
        Point::<2>::new(1.0, 0.0),
        Point::<2>::new(5.0, 5.0),
        Point::<2>::new(6.0, 5.0),
    ];
    let segs = vec![[0, 1], [2, 3], [4, 5], [1, 4]];
    let hits = find_segment_intersections(&pts, &segs);
    assert_eq!(hits.len(), 1);
    assert_eq!((hits[0].a, hits[0].b), (0, 1));
    assert!((hits[0].point - Point::<2>::new(0.5, 0.5)).norm() < 1e-14);
}
