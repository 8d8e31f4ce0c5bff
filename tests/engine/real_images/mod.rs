//! Segmentation at defaults (`{"problem": {"type": "segmentation", "image": …}}`
//! and nothing else) on a real image with a manual annotation (tests/data, see its
//! README) and on synthetic pictures with a known answer: Dice against the truth
//! and the number of objects found. Photographs and micrographs here; synthetic
//! pictures, volumes and empty results in the modules.

use shapeflow::export::{mask, objects, ObjectRow};
use shapeflow::jobs::{parse_spec, prepare, result_state, run_prepared, PreparedJob, StateResults};
use std::collections::HashMap;
use std::sync::atomic::AtomicBool;

const DEFAULTS: &str = r#"{"problem": {"type": "segmentation", "image": "input:image"}}"#;

/// Run `spec` on `image`; the mask (grid order, rows from the bottom), the number
/// of objects found and the prepared job.
fn segment(spec: &str, image: Vec<u8>) -> (Vec<bool>, usize, PreparedJob) {
    let (m, rows, job) = segment_objects(spec, image);
    (m, rows.len(), job)
}

/// As [`segment`], with the table of objects.
fn segment_objects(spec: &str, image: Vec<u8>) -> (Vec<bool>, Vec<ObjectRow>, PreparedJob) {
    let inputs: HashMap<String, Vec<u8>> = [("image".to_string(), image)].into();
    let job = prepare(parse_spec(spec).unwrap(), &inputs).unwrap();
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut ()).unwrap();
    let shown = result_state(&job, &out.last);
    let img = job.image.as_deref().unwrap();
    let m = mask(img, &shown.mesh);
    let rows = objects(img, &shown.mesh).1;
    eprintln!("stop {:?} after {} iterations; {} objects", out.stop, out.last.iteration, rows.len());
    (m, rows, job)
}

/// Uniform samples in `[0, 1)` from a xorshift generator started at `seed`: the
/// fixed noise of the synthetic pictures.
fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Dice of `got` (grid order) against `truth` (file order, rows from the top).
fn dice(got: &[bool], truth: &[bool], w: usize, h: usize) -> f64 {
    let (mut both, mut a, mut b) = (0usize, 0usize, 0usize);
    for r in 0..h {
        for c in 0..w {
            let g = got[c + w * (h - 1 - r)];
            let t = truth[c + w * r];
            both += (g && t) as usize;
            a += g as usize;
            b += t as usize;
        }
    }
    2.0 * both as f64 / (a + b) as f64
}

mod empty;
mod synthetic;
mod volumes;

/// Fluorescence microscopy, 512², 125 annotated nuclei of uneven brightness (the
/// image the min–max edge indicator found 0.05 of). Established tools, tuned:
/// Dice 0.84–0.89 with 73–88 components (scripts/compare_segmentation.py).
#[test]
fn nuclei_at_defaults() {
    let labels = image::load_from_memory(include_bytes!("../../data/nuclei_labels.png")).unwrap().to_luma16();
    let (w, h) = (labels.width() as usize, labels.height() as usize);
    let truth: Vec<bool> = labels.pixels().map(|p| p.0[0] > 0).collect();
    let (got, n, job) = segment(DEFAULTS, include_bytes!("../../data/nuclei.png").to_vec());
    let d = dice(&got, &truth, w, h);
    eprintln!("nuclei: dice {d:.4}, {n} objects (125 annotated); {:?}", job.segmentation);
    assert!(d >= 0.91, "dice {d}");
    assert!((80..=170).contains(&n), "{n} objects");
}

/// A photograph of 24 coins on a background with uneven illumination (tests/data,
/// from scikit-image). Without the illumination model, Otsu's threshold joins the
/// top row of coins to the bright top of the background. No annotation ships with
/// it: every coin (about 1,100 px² or more) must be found as one object, and
/// nothing else (the bright band along the photograph's top edge is background).
#[test]
fn coins_at_defaults() {
    let (_, rows, job) = segment_objects(DEFAULTS, include_bytes!("../../data/coins.png").to_vec());
    let setup = job.segmentation.as_ref().unwrap();
    let coins = rows.iter().filter(|r| r.size >= 500.0).count();
    let others: Vec<_> = rows.iter().filter(|r| r.size < 500.0).map(|r| (r.size, r.centroid.clone())).collect();
    eprintln!("coins: {coins} coins, others {others:?}; illumination {}", setup.illumination_range);
    assert_eq!(coins, 24);
    assert!(others.is_empty(), "{others:?}");
    assert!(setup.illumination_range > 0.05, "{}", setup.illumination_range);
}

/// A quantitative phase image of a single cell floating in saline (tests/data, from
/// scikit-image), 550×660, with a dark halo around the cell and a banding pattern in
/// the background that a white-noise estimate does not see. Its annotation here is
/// the disc through the cell's half-maximum edge (between the plateau inside and the
/// halo's minimum), read off the profiles along the row and the column through the
/// centre: centre (427.5, 373.75) px from the top left, diameter 126 px (127
/// across, 125.5 down). The cell must be the one object found.
#[test]
fn a_cell_in_a_phase_image() {
    let (w, h) = (550, 660);
    let truth: Vec<bool> =
        (0..w * h).map(|p| ((p % w) as f64 + 0.5 - 427.5).hypot((p / w) as f64 + 0.5 - 373.75) < 63.0).collect();
    let (got, n, job) = segment(DEFAULTS, include_bytes!("../../data/cell.png").to_vec());
    let d = dice(&got, &truth, w, h);
    eprintln!("cell: dice {d:.4}, {n} objects; {:?}", job.segmentation);
    assert_eq!(n, 1);
    assert!(d >= 0.96, "dice {d}");
}

/// scikit-image's horse silhouette (tests/data, 400×328 RGBA as it ships): one
/// object whose head, tail and hooves join it at necks. The split of touching
/// objects cut it into 10 before it asked for sides of comparable size and a
/// neck clearly below the smaller one; it must be one object, Dice ≥ 0.995
/// against the silhouette (its dark pixels).
#[test]
fn a_silhouette_with_legs_and_a_tail_is_one_object() {
    let horse = image::load_from_memory(include_bytes!("../../data/horse.png")).unwrap().to_luma8();
    let (w, h) = (horse.width() as usize, horse.height() as usize);
    let truth: Vec<bool> = horse.pixels().map(|p| p.0[0] < 128).collect();
    let (got, n, _) = segment(DEFAULTS, include_bytes!("../../data/horse.png").to_vec());
    let d = dice(&got, &truth, w, h);
    eprintln!("horse: dice {d:.4}, {n} objects");
    assert_eq!(n, 1);
    assert!(d >= 0.995, "dice {d}");
}

/// scikit-image's checkerboard (tests/data, 200², 8×8 squares of 25 px, light
/// squares 205–255): its 32 light squares touch at their corners, where the
/// contact rule holds them apart. Each step and the mesh management after it then
/// alternated between two energies, for 1,000 iterations before the convergence
/// test over a window of steps. The run ends `converged` within 300 iterations,
/// each light square one object.
#[test]
fn a_checkerboard_converges_with_its_32_squares() {
    let board = image::load_from_memory(include_bytes!("../../data/checkerboard.png")).unwrap().to_luma8();
    let (w, h) = (board.width() as usize, board.height() as usize);
    let truth: Vec<bool> = board.pixels().map(|p| p.0[0] > 127).collect();
    let inputs: HashMap<String, Vec<u8>> =
        [("image".to_string(), include_bytes!("../../data/checkerboard.png").to_vec())].into();
    let job = prepare(parse_spec(DEFAULTS).unwrap(), &inputs).unwrap();
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut ()).unwrap();
    let shown = result_state(&job, &out.last);
    let img = job.image.as_deref().unwrap();
    let d = dice(&mask(img, &shown.mesh), &truth, w, h);
    let n = objects(img, &shown.mesh).1.len();
    eprintln!("checkerboard: {:?} after {} iterations, dice {d:.4}, {n} objects", out.stop, out.last.iteration);
    assert_eq!(out.stop, shapeflow::flow::StopReason::Converged);
    assert!(out.last.iteration <= 300, "{} iterations", out.last.iteration);
    assert_eq!(n, 32);
    assert!(d >= 0.99, "dice {d}");
}

/// A PNG of 8-bit grey `pixels` (`w × h`, rows from the top).
fn png_gray8(pixels: &[u8], w: usize, h: usize) -> Vec<u8> {
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        pixels,
        w as u32,
        h as u32,
        image::ExtendedColorType::L8,
    )
    .unwrap();
    png
}
