//! Runs that find no object end successfully with an empty result.

use super::*;

/// An empty result is a result: a faint square whose contour costs more than its
/// region gains (`mu` large, within its bounds) shrinks away; the run ends
/// `vanished`, successfully, with an empty mask, an empty label image and no
/// objects.
#[test]
fn an_object_that_shrinks_away_is_an_empty_result() {
    let (w, h) = (64u32, 64u32);
    let img = image::GrayImage::from_fn(w, h, |x, y| {
        image::Luma([if (24..40).contains(&x) && (24..40).contains(&y) { 110 } else { 100 }])
    });
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
    let spec = r#"{"problem": {"type": "segmentation", "image": "input:image", "mu": 50}}"#;
    let inputs: HashMap<String, Vec<u8>> = [("image".to_string(), png)].into();
    let job = prepare(parse_spec(spec).unwrap(), &inputs).unwrap();
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut ()).unwrap();
    assert_eq!(out.stop, shapeflow::flow::StopReason::Vanished);
    assert!(out.note.unwrap().contains("no object"));
    let shown = result_state(&job, &out.last);
    let results = StateResults::new(&job, &shown);
    let mask = image::load_from_memory(&results.image_file("mask.png").unwrap().1).unwrap().to_luma8();
    assert!(mask.pixels().all(|p| p.0[0] == 0));
    let labels = image::load_from_memory(&results.image_file("labels.png").unwrap().1).unwrap().to_luma16();
    assert!(labels.pixels().all(|p| p.0[0] == 0));
    assert_eq!(results.shape_document()["objects"], serde_json::json!([]));
    let csv = String::from_utf8(results.image_file("objects.csv").unwrap().1).unwrap();
    assert_eq!(csv.lines().count(), 1, "{csv}");
}

/// An image in which the threshold keeps no object (here everything is below
/// `min_size`): the flow starts from the inscribed circle, which shrinks away; the
/// run ends `vanished`, successfully, with an empty mask, and the setup reports that
/// the threshold found no object.
#[test]
fn an_image_without_objects_gives_an_empty_result() {
    let mut img = image::GrayImage::from_pixel(48, 40, image::Luma([100]));
    img.put_pixel(5, 5, image::Luma([101]));
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
    let spec = r#"{"problem": {"type": "segmentation", "image": "input:image", "min_size": 1000}}"#;
    let inputs: HashMap<String, Vec<u8>> = [("image".to_string(), png)].into();
    let job = prepare(parse_spec(spec).unwrap(), &inputs).unwrap();
    assert_eq!(job.segmentation.as_ref().unwrap().initial_objects, 0);
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut ()).unwrap();
    assert_eq!(out.stop, shapeflow::flow::StopReason::Vanished);
    let shown = result_state(&job, &out.last);
    let results = StateResults::new(&job, &shown);
    let mask = image::load_from_memory(&results.image_file("mask.png").unwrap().1).unwrap().to_luma8();
    assert!(mask.pixels().all(|p| p.0[0] == 0));
    assert_eq!(results.shape_document()["objects"], serde_json::json!([]));
}
