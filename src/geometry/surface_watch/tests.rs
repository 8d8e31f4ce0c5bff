use super::*;
use crate::geometry::{box_surface, icosphere, surface_intersections, surface_union};

use crate::geometry::test_numbers::numbers;

/// Two spheres of radius 1 at `±(1 + gap/2)` on the x axis.
fn two_spheres(gap: f64, level: u32) -> (Vec<Point<3>>, Vec<[usize; 3]>) {
    let a = icosphere([-1.0 - gap / 2.0, 0.0, 0.0], 1.0, level).unwrap();
    let b = icosphere([1.0 + gap / 2.0, 0.0, 0.0], 1.0, level).unwrap();
    let two = surface_union(&[a, b]).unwrap();
    (two.positions().to_vec(), two.elements().to_vec())
}

/// Two spheres closing in, every vertex also jittered (a few by up to two mean
/// edges, which folds the surface): at every step the watch reports a meeting
/// whenever the exhaustive search of the new state finds one, and nothing while
/// the spheres are farther apart than the step moves them. The certificate
/// answers for most pairs: it is re-anchored, not drawn again, as the vertices move.
#[test]
fn the_watch_misses_no_intersection_of_an_approach_and_of_folds() {
    let (x0, t) = two_spheres(0.3, 3);
    let h = mean_edge(&x0, &t);
    let n = x0.len();
    let mut r = numbers(3);
    let mut watch = SurfaceWatch::default();
    let mut old = x0.clone();
    let (mut found, mut reported) = (0, 0);
    for step in 0..60 {
        // the spheres close by 0.01 a step, each vertex wanders by 0.05 h
        let mut new: Vec<Point<3>> = old
            .iter()
            .enumerate()
            .map(|(v, p)| {
                let side = if v < n / 2 { 1.0 } else { -1.0 };
                let jitter = Point::<3>::new(r() - 0.5, r() - 0.5, r() - 0.5) * 0.1 * h;
                p + Point::<3>::new(0.005 * side, 0.0, 0.0) + jitter
            })
            .collect();
        if step % 10 == 9 {
            // a few vertices pushed far: folds of the surface through itself
            for _ in 0..3 {
                let v = (r() * n as f64) as usize % n;
                new[v] += Point::<3>::new(r() - 0.5, r() - 0.5, r() - 0.5) * 4.0 * h;
            }
        }
        let exhaustive = surface_intersections(&new, &t, usize::MAX);
        let hits = watch.meetings(&old, &new, &t, usize::MAX);
        if !exhaustive.is_empty() {
            found += 1;
            assert!(!hits.is_empty(), "step {step}: the watch missed {exhaustive:?}");
            let mut hits = hits.clone();
            hits.sort_unstable();
            for p in &exhaustive {
                assert!(hits.binary_search(p).is_ok(), "step {step}: pair {p:?} missed");
            }
        }
        reported += usize::from(!hits.is_empty());
        if hits.is_empty() {
            old = new;
        }
    }
    assert!(found >= 3, "the folds were found: {found}");
    assert!(reported >= found);
    assert_eq!(watch.drawn, 1, "one certificate, re-anchored as it went: {watch:?}");
    assert!(watch.reanchored >= 1);
}

/// Far apart and moving little, the spheres need no pair tested; a gap shrinking
/// to nothing is reported by the first step that closes it, and not before.
#[test]
fn nothing_is_reported_until_the_spheres_touch() {
    let (x0, t) = two_spheres(0.2, 3);
    let n = x0.len();
    let mut watch = SurfaceWatch::default();
    let mut old = x0;
    for step in 0..30 {
        // each sphere moves by 0.004 towards the other: the gap closes by 0.008
        let new: Vec<Point<3>> = old
            .iter()
            .enumerate()
            .map(|(v, p)| p + Point::<3>::new(if v < n / 2 { 0.004 } else { -0.004 }, 0.0, 0.0))
            .collect();
        let hits = watch.meetings(&old, &new, &t, 1);
        let gap = 0.2 - 0.008 * (step + 1) as f64;
        // the polyhedra lie inside the spheres: they meet a little after the spheres
        if gap > 0.0 {
            assert!(hits.is_empty(), "step {step}: gap {gap}, reported {hits:?}");
        }
        if !surface_intersections(&new, &t, 1).is_empty() {
            assert!(!hits.is_empty(), "step {step}");
            return;
        }
        old = new;
    }
    panic!("the spheres never met");
}

/// A small sphere that jumps through a thin plate within one step, apart from it
/// at both ends (the discrete check finds nothing), is caught by the continuous
/// test; the same jump beside the plate is not reported.
#[test]
fn a_jump_through_a_thin_plate_is_caught() {
    let plate = box_surface([0.0; 3], [2.0, 2.0, 0.05], 8.0).unwrap();
    let ball = icosphere([0.0, 0.0, 0.3], 0.1, 2).unwrap();
    let both = surface_union(&[plate, ball]).unwrap();
    let (x, t) = (both.positions().to_vec(), both.elements().to_vec());
    let first_ball = both.num_vertices() - ball_vertices();
    let jump = |dz: f64, dx: f64| -> Vec<Point<3>> {
        x.iter().enumerate().map(|(v, p)| if v >= first_ball { p + Point::<3>::new(dx, 0.0, dz) } else { *p }).collect()
    };
    let through = jump(-0.6, 0.0);
    assert!(surface_intersections(&through, &t, 1).is_empty(), "apart at the end");
    assert!(!SurfaceWatch::default().meetings(&x, &through, &t, 1).is_empty(), "the pass through the plate");
    let beside = jump(-0.6, 6.0);
    assert!(SurfaceWatch::default().meetings(&x, &beside, &t, 1).is_empty(), "beside the plate");
    // the swept search alone (the driver's on a long step) says the same
    let swept = swept_surface_intersections(&x, &through, &t, usize::MAX);
    assert!(!swept.is_empty() && swept.windows(2).all(|w| w[0] < w[1]), "{swept:?}");
    assert!(swept_surface_intersections(&x, &beside, &t, 1).is_empty());
}

fn ball_vertices() -> usize {
    icosphere([0.0; 3], 1.0, 2).unwrap().num_vertices()
}
