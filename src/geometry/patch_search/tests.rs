use super::certify::{simple_loop, star_simple};
use super::*;
use crate::geometry::surface_intersections::mean_edge;
use crate::geometry::{box_surface, ellipsoid, icosphere, surface_intersections, surface_union, torus};
use robust::Coord;

use crate::geometry::test_numbers::numbers;

fn all_pairs(search: &mut PatchSearch, x: &[Point<3>], t: &[[usize; 3]]) -> Vec<(usize, usize)> {
    let mut found = search.intersections(x, t, usize::MAX);
    found.sort_unstable();
    let mut exhaustive = surface_intersections(x, t, usize::MAX);
    exhaustive.sort_unstable();
    assert_eq!(found, exhaustive, "the patch search and the exhaustive search differ");
    assert!(found.windows(2).all(|w| w[0] != w[1]), "a pair reported twice");
    found
}

/// Smooth closed surfaces, and a box (flat faces, straight rows of vertices,
/// right-angled edges): nothing meets, and nearly every patch is proved
/// embedded, so that few pairs are tested.
#[test]
fn smooth_surfaces_are_proved_apart_patch_by_patch() {
    let shapes = [
        icosphere([0.0; 3], 1.0, 4).unwrap(),
        ellipsoid([0.1, 0.0, 0.0], [1.0, 0.5, 0.3], 4).unwrap(),
        torus([0.0; 3], 1.0, 0.3, 96, 32).unwrap(),
        box_surface([0.0; 3], [8.0, 1.0, 1.0], 12.0).unwrap(),
    ];
    for mesh in shapes {
        let (x, t) = (mesh.positions().to_vec(), mesh.elements().to_vec());
        let mut search = PatchSearch::default();
        assert!(all_pairs(&mut search, &x, &t).is_empty());
        assert!(search.patches_searched > 20, "{} patches", search.patches_searched);
        assert!(
            search.embedded as f64 >= 0.95 * search.patches_searched as f64,
            "{} of {} patches embedded",
            search.embedded,
            search.patches_searched
        );
        assert!(search.tested < t.len() / 2, "{} pairs tested for {} triangles", search.tested, t.len());
        // the groups and seams proved embedded leave few pairs of patches
        assert!(search.groups + search.sealed > 0);
        assert!(search.neighbours < 2 * search.patches_searched, "{} pairs of patches", search.neighbours);
    }
}

/// Two spheres apart, in a thin lens of contact, and overlapping deeply: the
/// same pairs as the exhaustive search, `most` honoured.
#[test]
fn meeting_spheres_give_the_exhaustive_pairs() {
    let mut search = PatchSearch::default();
    for (gap, meet) in [(0.01, false), (-0.01, true), (-0.6, true)] {
        let a = icosphere([-1.0 - gap / 2.0, 0.0, 0.0], 1.0, 3).unwrap();
        let b = icosphere([1.0 + gap / 2.0, 0.0, 0.0], 1.0, 3).unwrap();
        let two = surface_union(&[a, b]).unwrap();
        let (x, t) = (two.positions().to_vec(), two.elements().to_vec());
        let found = all_pairs(&mut search, &x, &t);
        assert_eq!(!found.is_empty(), meet, "gap {gap}");
        if meet {
            assert_eq!(search.intersections(&x, &t, 1).len(), 1);
        }
    }
}

/// A state searched in full is answered again from that search (a flow's trial
/// step, searched by its contact rule and then by its check); a state moved
/// by a hair is searched; a caller's answer is kept until forgotten.
#[test]
fn a_state_searched_in_full_is_answered_without_a_search() {
    let a = icosphere([-0.95, 0.0, 0.0], 1.0, 3).unwrap();
    let b = icosphere([0.95, 0.02, 0.0], 1.0, 3).unwrap();
    let two = surface_union(&[a, b]).unwrap();
    let (x, t) = (two.positions().to_vec(), two.elements().to_vec());
    let mut search = PatchSearch::default();
    let pairs = all_pairs(&mut search, &x, &t);
    assert!(pairs.len() > 10, "{}", pairs.len());
    search.tested = 0;
    assert_eq!(search.intersections(&x, &t, usize::MAX), pairs);
    assert_eq!(search.intersections(&x, &t, 1), pairs[..1]);
    assert_eq!(search.tested, 0, "answered without a search");
    let mut y = x.clone();
    y[0][0] += 1e-9;
    all_pairs(&mut search, &y, &t);
    assert!(search.tested > 0, "a moved state is searched");
    search.remember(&x, &t, vec![(1, 3)]);
    assert_eq!(search.intersections(&x, &t, usize::MAX), [(1, 3)]);
    search.forget();
    let mut again = search.intersections(&x, &t, usize::MAX);
    again.sort_unstable();
    assert_eq!(again, pairs);
}

/// A sphere jittered by up to 0.3 to 3 mean edges (folds, triangles flipped,
/// sheets through each other), and a flattened ellipsoid pushed through itself:
/// the same pairs as the exhaustive search in every case.
#[test]
fn folded_and_jittered_surfaces_give_the_exhaustive_pairs() {
    let mesh = icosphere([0.0; 3], 1.0, 3).unwrap();
    let t = mesh.elements().to_vec();
    let h = mean_edge(mesh.positions(), &t);
    let mut r = numbers(7);
    let mut search = PatchSearch::default();
    let mut meeting = 0;
    for amplitude in [0.3, 0.6, 1.0, 3.0] {
        for _ in 0..3 {
            let x = jittered(mesh.positions(), amplitude * h, &mut r);
            meeting += usize::from(!all_pairs(&mut search, &x, &t).is_empty());
        }
    }
    assert!(meeting >= 6, "{meeting} of 12 jittered spheres meet themselves");
    // a pancake whose top is pushed down through its bottom near the centre
    let pancake = ellipsoid([0.0; 3], [1.0, 1.0, 0.05], 4).unwrap();
    let t = pancake.elements().to_vec();
    let x: Vec<Point<3>> = pancake
        .positions()
        .iter()
        .map(|p| {
            let dip = if p[2] > 0.0 { 0.2 * (-(p[0] * p[0] + p[1] * p[1]) / 0.05).exp() } else { 0.0 };
            Point::<3>::new(p[0], p[1], p[2] - dip)
        })
        .collect();
    assert!(!all_pairs(&mut search, &x, &t).is_empty());
}

/// A connectivity that is not a closed manifold (an open strip) gets patches of
/// one triangle: the search is the exhaustive one.
#[test]
fn an_open_surface_is_searched_triangle_by_triangle() {
    let x = vec![
        Point::<3>::new(0.0, 0.0, 0.0),
        Point::<3>::new(1.0, 0.0, 0.0),
        Point::<3>::new(0.0, 1.0, 0.0),
        Point::<3>::new(0.2, 0.2, -0.5),
        Point::<3>::new(0.3, 0.2, 0.5),
        Point::<3>::new(0.2, 0.3, 0.5),
    ];
    let t = vec![[0, 1, 2], [3, 4, 5]];
    let mut search = PatchSearch::default();
    assert_eq!(all_pairs(&mut search, &x, &t), vec![(0, 1)]);
    assert_eq!((search.patches_searched, search.embedded), (2, 0));
}

#[test]
fn simple_loops() {
    let c = |pts: &[(f64, f64)]| pts.iter().map(|&(x, y)| Coord { x, y }).collect::<Vec<_>>();
    assert!(simple_loop(&c(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])));
    // straight runs along a side
    assert!(simple_loop(&c(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0)])));
    // a bow tie, a spike folding back along itself, a loop touching itself at a corner
    assert!(!simple_loop(&c(&[(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)])));
    assert!(!simple_loop(&c(&[(0.0, 0.0), (2.0, 0.0), (1.0, 0.0), (1.0, 1.0)])));
    assert!(!simple_loop(&c(&[(0.0, 0.0), (2.0, 0.0), (1.0, 1.0), (2.0, 2.0), (0.0, 2.0), (1.0, 1.0)])));
    // a corner of one edge on another
    assert!(!simple_loop(&c(&[(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (1.0, 0.0), (0.0, 2.0)])));
    // the star test: a polygon seen turning one way from its centre, once; not
    // twice (a pentagram), nor the other way, nor with an edge turning back
    let around = |turns: f64, corners: usize| {
        let a = |i: usize| turns * std::f64::consts::TAU * i as f64 / corners as f64;
        c(&(0..corners).map(|i| (a(i).cos(), a(i).sin())).collect::<Vec<_>>())
    };
    assert!(star_simple(&around(1.0, 7), true) && simple_loop(&around(1.0, 7)));
    assert!(!star_simple(&around(1.0, 7), false) && !star_simple(&around(-1.0, 7), true));
    assert!(star_simple(&around(-1.0, 7), false));
    assert!(!star_simple(&around(2.0, 5), true) && !simple_loop(&around(2.0, 5)));
    let notch = c(&[(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (1.0, 2.0), (1.5, 1.5), (0.0, 2.0)]);
    assert!(!star_simple(&notch, true) && simple_loop(&notch));
}

/// Small jitters (0.1 to 0.4 mean edges) of a torus, a box and two spheres a
/// tenth of an edge apart, 24 seeds: most patches still embedded, some pairs
/// meeting across patches or within the ones that are not; the exhaustive pairs
/// every time.
#[test]
fn slightly_jittered_surfaces_give_the_exhaustive_pairs() {
    let a = icosphere([-1.02, 0.0, 0.0], 1.0, 3).unwrap();
    let b = icosphere([1.02, 0.0, 0.0], 1.0, 3).unwrap();
    let shapes = [
        torus([0.0; 3], 1.0, 0.3, 64, 24).unwrap(),
        box_surface([0.0; 3], [4.0, 1.0, 1.0], 8.0).unwrap(),
        surface_union(&[a, b]).unwrap(),
    ];
    let (mut embedded, mut patches, mut meeting) = (0, 0, 0);
    for (k, mesh) in shapes.iter().enumerate() {
        let t = mesh.elements().to_vec();
        let h = mean_edge(mesh.positions(), &t);
        let mut search = PatchSearch::default();
        for seed in 0..8 {
            let mut r = numbers(100 * k as u64 + seed);
            let amplitude = 0.1 + 0.3 * r();
            let x = jittered(mesh.positions(), amplitude * h, &mut r);
            meeting += usize::from(!all_pairs(&mut search, &x, &t).is_empty());
            (embedded, patches) = (embedded + search.embedded, patches + search.patches_searched);
        }
    }
    assert!(meeting >= 4, "{meeting} of 24 meet");
    assert!(2 * embedded >= patches, "{embedded} of {patches} patches embedded");
}

/// One search kept while an ellipsoid turns by 90° in steps of 10° (the
/// connectivity unchanged, the patches cut for the first pose): the exhaustive
/// pairs at every pose, and nearly every patch embedded at each (a patch picks its
/// plane at each search). A crumpled state, on which most patches are not, has
/// them cut again at the next search.
#[test]
fn patches_follow_a_turning_and_a_crumpling_surface() {
    let mesh = ellipsoid([0.0; 3], [1.0, 0.6, 0.3], 4).unwrap();
    let t = mesh.elements().to_vec();
    let mut search = PatchSearch::default();
    for step in 0..=9 {
        let (s, c) = (f64::from(step) * 10f64.to_radians()).sin_cos();
        let x: Vec<Point<3>> =
            mesh.positions().iter().map(|p| Point::<3>::new(c * p[0] - s * p[2], p[1], s * p[0] + c * p[2])).collect();
        assert!(all_pairs(&mut search, &x, &t).is_empty());
        assert!(
            search.embedded * 10 >= 9 * search.patches_searched,
            "{} of {}",
            search.embedded,
            search.patches_searched
        );
        assert!(!search.stale);
    }
    let h = mean_edge(mesh.positions(), &t);
    let mut r = numbers(11);
    let crumpled: Vec<Point<3>> =
        mesh.positions().iter().map(|p| p + Point::<3>::new(r() - 0.5, r() - 0.5, r() - 0.5) * h).collect();
    all_pairs(&mut search, &crumpled, &t);
    assert!(search.stale, "{} of {} patches embedded", search.embedded, search.patches_searched);
    // patches cut for the crumpled state itself are kept for it
    let mut fresh = PatchSearch::default();
    for _ in 0..2 {
        all_pairs(&mut fresh, &crumpled, &t);
        assert!(!fresh.stale, "{} of {} embedded", fresh.embedded, fresh.patches_searched);
    }
    assert!(all_pairs(&mut search, mesh.positions(), &t).is_empty());
    assert!(!search.stale);
}

/// Two arcs that close a simple loop, and the ways they fail to: crossing,
/// touching away from the junctions, folding back at one.
#[test]
fn arcs_close_a_simple_loop_only_when_apart() {
    let c = |x: f64, y: f64| Coord { x, y };
    // P from (1, 0) over the top to (-1, 0); Q back along the bottom
    let p = [c(1.0, 0.0), c(0.0, 1.0), c(-1.0, 0.0)];
    assert!(seams::arcs_apart(&p, &[c(-1.0, 0.0), c(0.0, -1.0), c(1.0, 0.0)]));
    assert!(seams::arcs_apart(&p, &[c(-1.0, 0.0), c(1.0, 0.0)]));
    // Q crossing P, touching it at a corner, folding back along its last edge
    assert!(!seams::arcs_apart(&p, &[c(-1.0, 0.0), c(0.5, 2.0), c(0.5, -1.0), c(1.0, 0.0)]));
    assert!(!seams::arcs_apart(&p, &[c(-1.0, 0.0), c(0.0, 1.0), c(1.0, 0.0)]));
    assert!(!seams::arcs_apart(&p, &[c(-1.0, 0.0), c(-0.5, 0.5), c(0.0, -1.0), c(1.0, 0.0)]));
    // a single edge each is no loop
    assert!(!seams::arcs_apart(&[c(1.0, 0.0), c(-1.0, 0.0)], &[c(-1.0, 0.0), c(1.0, 0.0)]));
}

/// Two connectivities searched in turn (a managed state and the state before
/// it), and a state searched again after its positions changed: each answer is
/// the exhaustive search's (the two cuts kept, and the answer kept for one
/// state, serve only their own input), and both cuts are kept.
#[test]
fn kept_cuts_and_answers_serve_only_their_own_input() {
    let overlapping =
        surface_union(&[icosphere([-0.45, 0.0, 0.0], 0.5, 3).unwrap(), icosphere([0.45, 0.0, 0.0], 0.5, 3).unwrap()])
            .unwrap();
    let single = icosphere([0.0; 3], 1.0, 3).unwrap();
    let (xa, ta) = (overlapping.positions().to_vec(), overlapping.elements().to_vec());
    let (xb, tb) = (single.positions().to_vec(), single.elements().to_vec());
    let mut search = PatchSearch::default();
    let meeting = all_pairs(&mut search, &xa, &ta);
    assert!(!meeting.is_empty());
    assert!(all_pairs(&mut search, &xb, &tb).is_empty());
    assert!(search.knows(&ta) && search.knows(&tb));
    assert_eq!(all_pairs(&mut search, &xa, &ta), meeting);
    assert_eq!(search.intersections_of_state(&xa, &ta), meeting);
    assert_eq!(search.intersections_of_state(&xa, &ta), meeting, "the kept answer");
    // the second sphere moved away: the kept answer is not given for it
    let apart: Vec<Point<3>> = (xa.iter().enumerate())
        .map(|(v, p)| if v >= xa.len() / 2 { p + Point::<3>::new(0.2, 0.0, 0.0) } else { *p })
        .collect();
    assert!(search.intersections_of_state(&apart, &ta).is_empty());
    assert!(all_pairs(&mut search, &apart, &ta).is_empty());
}

/// `x` with every vertex moved by up to `reach` along each axis (uniform, from `r`).
fn jittered(x: &[Point<3>], reach: f64, r: &mut impl FnMut() -> f64) -> Vec<Point<3>> {
    x.iter().map(|p| p + Point::<3>::new(r() - 0.5, r() - 0.5, r() - 0.5) * (2.0 * reach)).collect()
}
