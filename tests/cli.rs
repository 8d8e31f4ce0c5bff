//! The `shapeflow run` command end to end.

use std::process::Command;

fn shapeflow() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shapeflow"))
}

#[test]
fn run_writes_shape_and_history_and_reports_the_stop_reason() {
    let dir = tempfile::tempdir().unwrap();
    let out = shapeflow().args(["run", "examples/circle.json", "--out"]).arg(dir.path()).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout} {}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("stopped: end_time after 2500 iterations"), "{stdout}");
    let took = stdout.lines().last().unwrap();
    assert!(
        took.starts_with("took ") && took.contains(" s to run, ") && took.ends_with(" s to write the results"),
        "{took}"
    );
    let shape: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("shape.json")).unwrap()).unwrap();
    assert_eq!(shape["dimension"], 2);
    assert_eq!(shape["iteration"], 2500);
    // evolution.glb: one frame per checkpoint (every 250 iterations), in order, the
    // frames made on a second thread while the run went on
    let glb = std::fs::read(dir.path().join("evolution.glb")).unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let frames: Vec<u64> =
        doc["nodes"].as_array().unwrap().iter().filter_map(|n| n["extras"]["iteration"].as_u64()).collect();
    assert_eq!(frames, (0..=10).map(|k| 250 * k).collect::<Vec<u64>>());
    assert_eq!(doc["extras"]["frames"], 11);
    let verts = shape["components"][0]["vertices"].as_array().unwrap();
    assert_eq!(verts.len(), 256);
    let exact = 0.5f64.sqrt();
    for v in verts {
        let r = (v[0].as_f64().unwrap().powi(2) + v[1].as_f64().unwrap().powi(2)).sqrt();
        assert!((r - exact).abs() < 1e-3, "radius {r}");
    }
    let csv = std::fs::read_to_string(dir.path().join("energy.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows[0].starts_with("iteration,time,tau,energy,vertices"));
    assert_eq!(rows.len(), 1 + 2501);
    let energies: Vec<f64> = rows[1..].iter().map(|r| r.split(',').nth(3).unwrap().parse().unwrap()).collect();
    assert!(energies.windows(2).all(|w| w[1] < w[0]));
    // perimeter of the final circle
    assert!((energies[2500] - 2.0 * std::f64::consts::PI * exact).abs() < 1e-2);

    // resume from the written checkpoint with a later end time
    let spec = dir.path().join("longer.json");
    std::fs::write(
        &spec,
        std::fs::read_to_string("examples/circle.json").unwrap().replace("\"end_time\": 0.25", "\"end_time\": 0.3"),
    )
    .unwrap();
    let out2 = shapeflow()
        .arg("run")
        .arg(&spec)
        .arg("--out")
        .arg(dir.path().join("more"))
        .arg("--resume")
        .arg(dir.path().join("checkpoint.json"))
        .output()
        .unwrap();
    let stdout2 = String::from_utf8_lossy(&out2.stdout);
    assert!(stdout2.contains("stopped: end_time after 3000 iterations"), "{stdout2}");
}

#[test]
fn bad_spec_exits_nonzero_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let spec = dir.path().join("bad.json");
    std::fs::write(&spec, r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1}, "flow": {"tau": -0.5}}"#).unwrap();
    let out = shapeflow().arg("run").arg(&spec).arg("--out").arg(dir.path().join("o")).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("flow.tau: must be a positive number"), "{err}");
    assert!(err.contains("bad.json"), "{err}");
    let out = shapeflow().args(["run", "does-not-exist.json", "--out"]).arg(dir.path()).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("does-not-exist.json"));
    let out = shapeflow()
        .args(["run", "examples/circle.json", "--input", "nonsense", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("NAME=PATH"));
}

#[test]
fn uploaded_mesh_runs_through_input() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("cube.obj");
    // unit cube, outward faces
    let mut s = String::new();
    for z in [0.0, 1.0] {
        for y in [0.0, 1.0] {
            for x in [0.0, 1.0] {
                s += &format!("v {x} {y} {z}\n");
            }
        }
    }
    s += "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
    std::fs::write(&obj, s).unwrap();
    let spec = dir.path().join("spec.json");
    std::fs::write(&spec, r#"{"problem": {"type": "surface_diffusion"}, "initial": {"shape": "mesh", "file": "input:cube"}, "flow": {"tau": 1e-4, "max_iterations": 5}}"#).unwrap();
    let out = shapeflow()
        .arg("run")
        .arg(&spec)
        .arg("--out")
        .arg(dir.path().join("o"))
        .arg("--input")
        .arg(format!("cube={}", obj.display()))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let shape: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("o/shape.json")).unwrap()).unwrap();
    assert_eq!(shape["dimension"], 3);
    assert_eq!(shape["triangles"].as_array().unwrap().len(), 12);
}

/// Segmentation from the command line: mask.png, overlay.png and pixel coordinates.
#[test]
fn run_segments_an_image_and_writes_mask_and_overlay() {
    let dir = tempfile::tempdir().unwrap();
    let out = shapeflow()
        .args(["run", "examples/segment_star.json", "--input", "image=examples/data/star.png", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout} {}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("stopped: converged"), "{stdout}");
    let mask = image::open(dir.path().join("mask.png")).unwrap().to_luma8();
    assert_eq!(mask.dimensions(), (128, 128));
    // the star r = 34 (1 + 0.3 cos 5θ) has area π 34² (1 + 0.3²/2)
    let area = mask.pixels().filter(|p| p.0[0] == 255).count() as f64;
    let exact = std::f64::consts::PI * 34.0 * 34.0 * 1.045;
    assert!((area / exact - 1.0).abs() < 0.03, "{area} {exact}");
    // the mask is upright: the star's tip at angle 0 points right (column 102, row 64)
    assert_eq!(mask.get_pixel(100, 64).0[0], 255);
    assert_eq!(mask.get_pixel(64, 100).0[0], 0);
    let overlay = image::open(dir.path().join("overlay.png")).unwrap().to_rgb8();
    assert_eq!(overlay.dimensions(), (128, 128));
    assert!(overlay.pixels().filter(|p| p.0 == [230, 30, 30]).count() > 200);
    let shape: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("shape.json")).unwrap()).unwrap();
    assert_eq!(shape["image"]["width"], 128);
    let c = &shape["components"][0];
    let (v, p) = (&c["vertices"][0], &c["pixels"][0]);
    assert!((p[0].as_f64().unwrap() - (v[0].as_f64().unwrap() * 128.0 - 0.5)).abs() < 1e-9);
    assert!((p[1].as_f64().unwrap() - (127.5 - v[1].as_f64().unwrap() * 128.0)).abs() < 1e-9);
}

/// A 3D volume from NRRD: mask.nrrd of the two balls, and the same mask and the
/// labels as NIfTI-1, on the same grid.
#[test]
fn run_segments_a_volume_and_writes_an_nrrd_mask() {
    let dir = tempfile::tempdir().unwrap();
    let out = shapeflow()
        .args(["run", "examples/segment_balls.json", "--input", "volume=examples/data/balls.nrrd", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let bytes = std::fs::read(dir.path().join("mask.nrrd")).unwrap();
    let grid = shapeflow::imaging::parse_nrrd("mask", &bytes, &Default::default()).unwrap();
    assert_eq!(grid.dims, [48, 48, 48]);
    let inside = grid.values.iter().filter(|&&v| v == 1.0).count() as f64;
    // two balls of radius 8.5 whose centres are 15 apart: 2 V - lens
    let (r, d) = (8.5f64, 15.0f64);
    let lens = std::f64::consts::PI * (2.0 * r - d).powi(2) * (d * d + 4.0 * d * r) / (12.0 * d);
    let exact = 2.0 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) - lens;
    // (the balloon force keeps the surface about 0.4 px inside on this small volume)
    assert!((inside / exact - 1.0).abs() < 0.15, "{inside} {exact}");
    let nifti = |name: &str| {
        let bytes = std::fs::read(dir.path().join(name)).unwrap();
        shapeflow::imaging::decode_nifti(name, &bytes, &Default::default()).unwrap()
    };
    let (mask, labels) = (nifti("mask.nii.gz"), nifti("labels.nii.gz"));
    assert_eq!((mask.dims, &mask.values), (grid.dims, &grid.values));
    assert!(labels.values.iter().zip(&grid.values).all(|(l, m)| (*l > 0.0) == (*m == 1.0)));
    assert_eq!(mask.placement.spacing(), grid.placement.spacing());
}
