//! The surgery table of the management bench: two spheres of 20,484 vertices
//! 0.004 apart merged (zipped, rebuilt, and as the manager does it), the
//! rebuild's cut at the bridge, and the pinch-off cut on a prism.

use super::common::time_it;
use shapeflow::flow::{MeshManager, SurfaceManager};
use shapeflow::geometry::{icosphere, Point};
use std::hint::black_box;

pub fn table() {
    let a = icosphere([-1.002, 0.0, 0.0], 1.0, 5).unwrap();
    let b = icosphere([1.002, 0.0, 0.0], 1.0, 5).unwrap();
    let two = shapeflow::geometry::surface_union(&[a, b]).unwrap();
    let spacing = shapeflow::geometry::edge_statistics(&two).0;
    use shapeflow::flow::surgery::{rebuild, Operation};
    let t_merge = time_it(0.5, || {
        black_box(rebuild(&two, spacing, Operation::Merge { blend: 2.0 * spacing }).unwrap());
    });
    let one = rebuild(&two, spacing, Operation::Merge { blend: 2.0 * spacing }).unwrap().unwrap();
    // the manager's merge: zipped on the mesh (the rebuild on its grid, 4 h_min,
    // is its fallback), tidied by the adaptation and regularization
    let (params, pinch) = SurfaceManager::defaults_for(&two);
    let surgery = Some(shapeflow::flow::Surgery { merge: true, conserve: true });
    let mut merger = SurfaceManager {
        regularize: true,
        sweeps: 3,
        adapt: true,
        params,
        pinch_curvature: Some(pinch),
        surgery,
        declined: None,
    };
    let zip = || {
        let (p, q) = shapeflow::geometry::closest_facing_vertices(&two, spacing).expect("facing poles");
        shapeflow::geometry::zip_sheets(&two, p, q, spacing).expect("zipped")
    };
    let t_zip = time_it(0.5, || drop(black_box(zip())));
    let t_managed = time_it(0.5, || {
        black_box(merger.merge(&two).unwrap());
    });
    let tidied = merger.merge(&two).unwrap();
    let cut = Operation::Cut { at: Point::<3>::zeros(), radius: 3.0 * spacing, depth: 2.0 * spacing };
    let t_cut = time_it(0.5, || {
        black_box(rebuild(&one, spacing, cut).unwrap());
    });
    println!();
    println!("| surgery | vertices before → after | time (ms) |");
    println!("|---|---:|---:|");
    println!(
        "| merge of two spheres 0.004 apart, zipped (the zipper alone) | {} → {} | {:.1} |",
        two.num_vertices(),
        zip().num_vertices(),
        t_zip * 1e3
    );
    println!(
        "| the same, rebuilt (a grid of the mean edge; the zipper's fallback) | {} → {} | {:.0} |",
        two.num_vertices(),
        one.num_vertices(),
        t_merge * 1e3
    );
    let parted = rebuild(&one, spacing, cut).unwrap().unwrap();
    println!("| cut at the bridge | {} → {} | {:.0} |", one.num_vertices(), parted.num_vertices(), t_cut * 1e3);
    println!(
        "| the manager's merge (zipped, tidied, volume restored) | {} → {} | {:.0} |",
        two.num_vertices(),
        tidied.num_vertices(),
        t_managed * 1e3
    );
    // the pinch-off cut on the mesh itself: the triangles within a ball around a
    // neck removed, the holes capped (before the manager's two rounds of
    // tidying); the neck here the middle of an 8×1×1 prism, the ball of radius 0.8
    // taking its whole cross-section
    let prism = shapeflow::geometry::box_surface([0.0; 3], [8.0, 1.0, 1.0], 24.0).unwrap();
    let t_neck = time_it(0.5, || {
        black_box(shapeflow::geometry::cut_neck(&prism, Point::<3>::zeros(), 0.8));
    });
    let capped = shapeflow::geometry::cut_neck(&prism, Point::<3>::zeros(), 0.8).expect("the prism is cut");
    println!(
        "| pinch-off cut on the mesh (a prism's middle, {} parts) | {} → {} | {:.1} |",
        capped.component_labels().1,
        prism.num_vertices(),
        capped.num_vertices(),
        t_neck * 1e3
    );
}
