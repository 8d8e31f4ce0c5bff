//! Invalid specs, meshes and files give typed errors that name the field, index or file.

mod gltf_files;

use shapeflow::geometry::{circle, icosphere, polygon, CurveMesh, Mesh, MeshError, Point, SurfaceMesh};
use shapeflow::imaging::Subject;
use shapeflow::jobs::{parse_spec, prepare, read_mesh_file, AnyMesh, MeshFileError};
use std::collections::HashMap;

fn spec_error(json: &str) -> String {
    let no_inputs = HashMap::new();
    match parse_spec(json) {
        Err(e) => e.to_string(),
        Ok(spec) => prepare(spec, &no_inputs).expect_err("spec should be rejected").to_string(),
    }
}

const GOOD: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0}}"#;

#[test]
fn good_spec_prepares_with_defaults() {
    let job = prepare(parse_spec(GOOD).unwrap(), &HashMap::new()).unwrap();
    assert!(matches!(job.mesh, AnyMesh::Curve(ref m) if m.num_vertices() == 128));
    assert_eq!(job.settings.tau, 1e-3);
    assert!(job.settings.backtracking);
    assert_eq!(job.checkpoint_every, 10);
}

#[test]
fn spec_errors_name_the_field() {
    let cases = [
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0}, "flow": {"tau": -1}}"#,
            "flow.tau",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0}, "flow": {"taux": 1}}"#,
            "flow.taux",
        ),
        (
            r#"{"problem": {"type": "curvature_flow", "gama": 1}, "initial": {"shape": "circle", "radius": 1.0}}"#,
            "problem.gama",
        ),
        (r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 0}}"#, "initial.radius"),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1, "resolution": 2}}"#,
            "initial.resolution",
        ),
        (r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "hexagon"}}"#, "initial.shape"),
        (r#"{"problem": {"type": "nonsense"}, "initial": {"shape": "circle", "radius": 1}}"#, "problem.type"),
        (
            r#"{"problem": {"type": "segmentation", "image": "input:image"}, "initial": {"shape": "circle", "radius": 1}}"#,
            "problem.image",
        ),
        (r#"{"problem": {"type": "segmentation", "image": "image.png"}}"#, "problem.image"),
        (r#"{"problem": {"type": "segmentation", "image": 3}}"#, "problem.image"),
        (r#"{"problem": {"type": "curvature_flow"}}"#, "initial"),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "polygon", "points": [[0,0],[1,1],[1,0],[0,1]]}}"#,
            "initial",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "union", "parts": [{"shape": "circle", "radius": 1}, {"shape": "circle", "radius": -2}]}}"#,
            "initial.parts[1].radius",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "sphere", "radius": 1, "resolution": 12}}"#,
            "initial.resolution",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "mesh", "file": "input:shape"}}"#,
            "initial.file",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1}, "output": {"checkpoint_every": 0}}"#,
            "output.checkpoint_every",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1}, "flow": {"tau": NaN}}"#,
            "(document)",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1}, "flow": {"tau": 1e-3, "tau_min": 1}}"#,
            "flow.tau_min",
        ),
    ];
    let mut wrong = Vec::new();
    for (json, field) in cases {
        let msg = spec_error(json);
        if !msg.starts_with(&format!("{field}:")) {
            wrong.push(format!("expected an error naming {field}, got {msg:?}"));
        }
    }
    assert!(wrong.is_empty(), "{wrong:#?}");
    assert!(spec_error(r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "polygon", "points": [[0,0],[1,1],[1,0],[0,1]]}}"#).contains("intersect"));
    // a flat box is counted exactly before it is built (found by fuzzing: the count
    // assumed a cube, 6.2e5 here, and 7.6 million vertices took 20 s to build)
    let e = spec_error(
        r#"{"problem": {"type": "surface_diffusion"}, "initial": {"shape": "box", "size": [420, 1, 110], "resolution": 9}}"#,
    );
    assert!(e.starts_with("initial.resolution:") && e.contains("7570262 vertices"), "{e}");
    // likewise a fat torus, and parts that are each within the limit but not together
    let e = spec_error(
        r#"{"problem": {"type": "surface_diffusion"}, "initial": {"shape": "torus", "major_radius": 1, "minor_radius": 0.9, "resolution": 4096}}"#,
    );
    assert!(e.starts_with("initial.resolution:") && e.contains("15097856 vertices"), "{e}");
    let e = spec_error(
        r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "union", "parts": [{"shape": "circle", "radius": 1, "resolution": 1500000}, {"shape": "circle", "center": [3, 0], "radius": 1, "resolution": 1500000}]}}"#,
    );
    assert!(e.starts_with("initial.parts[1]:") && e.contains("in all"), "{e}");
    let boxed = r#"{"problem": {"type": "surface_diffusion"}, "initial": {"shape": "box", "size": [3, 1, 2], "resolution": 4}}"#;
    let job = prepare(parse_spec(boxed).unwrap(), &HashMap::new()).unwrap();
    // 12 × 4 × 8 cells: 13·5·9 − 11·3·7 vertices
    assert!(matches!(job.mesh, AnyMesh::Surface(ref m) if m.num_vertices() == 354));
}

fn image_error(json: &str, inputs: &[(&str, Vec<u8>)]) -> String {
    let files: HashMap<String, Vec<u8>> = inputs.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
    prepare(parse_spec(json).unwrap(), &files).expect_err("should be rejected").to_string()
}

fn gray_png(w: u32, h: u32, data: &[u8]) -> Vec<u8> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out).write_image(data, w, h, image::ExtendedColorType::L8).unwrap();
    out
}

#[test]
fn bad_images_give_errors_naming_the_input() {
    let spec = r#"{"problem": {"type": "segmentation", "image": "input:picture"}}"#;
    let good = gray_png(16, 16, &(0..=255).collect::<Vec<u8>>());
    // corrupt: a PNG cut in half
    let e = image_error(spec, &[("picture", good[..good.len() / 2].to_vec())]);
    assert!(e.starts_with("problem.image: input `picture`:"), "{e}");
    // not an image at all
    let e = image_error(spec, &[("picture", b"hello world".to_vec())]);
    assert!(e.contains("input `picture`") && e.contains("PNG"), "{e}");
    // 0×0: a PNG header claiming zero size
    let mut zero = good.clone();
    zero[16..24].copy_from_slice(&[0; 8]);
    let e = image_error(spec, &[("picture", zero)]);
    assert!(e.contains("input `picture`"), "{e}");
    // too small, constant, empty
    let e = image_error(spec, &[("picture", gray_png(2, 9, &[7; 18]))]);
    assert!(e.contains("at least 4"), "{e}");
    let e = image_error(spec, &[("picture", gray_png(8, 8, &[7; 64]))]);
    assert!(e.contains("constant"), "{e}");
    let e = image_error(spec, &[("picture", Vec::new())]);
    assert!(e.contains("empty"), "{e}");
    // NRRD with a wrong payload size, and a 2D image with a 3D initial shape
    let nrrd = b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 8 8 8\nencoding: raw\n\n0123".to_vec();
    let e = image_error(spec, &[("picture", nrrd)]);
    assert!(e.contains("input `picture`") && e.contains("512 expected"), "{e}");
    let e = image_error(
        r#"{"problem": {"type": "segmentation", "image": "input:picture"}, "initial": {"shape": "sphere", "radius": 0.3}}"#,
        &[("picture", good.clone())],
    );
    assert!(e.starts_with("initial:"), "{e}");
    let e = image_error(
        r#"{"problem": {"type": "segmentation", "image": "input:picture", "sigma": -1}}"#,
        &[("picture", good.clone())],
    );
    assert!(e.starts_with("problem.sigma:"), "{e}");
    // a smoothing far wider than the image leaves it constant: the smoothing is
    // named, not the image
    let e = image_error(
        r#"{"problem": {"type": "segmentation", "image": "input:picture", "sigma": 64}}"#,
        &[("picture", good.clone())],
    );
    assert!(e.starts_with("problem.sigma:") && e.contains("16 × 16") && e.contains("smaller"), "{e}");
    let e = image_error(
        r#"{"problem": {"type": "segmentation", "image": "input:picture", "lambda_final": -2}}"#,
        &[("picture", good.clone())],
    );
    assert!(e.starts_with("problem.lambda_final:") && e.contains("-2"), "{e}");
    // wrong types and unknown fields of the segmentation body are named too
    for (body, field) in [
        (r#""edge_refinement": "yes""#, "problem.edge_refinement:"),
        (r#""lambda": "large""#, "problem.lambda:"),
        (r#""sigmaa": 1"#, "problem.sigmaa:"),
    ] {
        let spec = format!(r#"{{"problem": {{"type": "segmentation", "image": "input:picture", {body}}}}}"#);
        let e = parse_spec(&spec).expect_err("should be rejected").to_string();
        assert!(e.starts_with(field), "{e}");
    }
    // slice stacks: sizes must agree, and the failing slice is named
    let e = image_error(
        r#"{"problem": {"type": "segmentation", "image": ["input:a", "input:b", "input:c", "input:d"]}}"#,
        &[("a", good.clone()), ("b", good.clone()), ("c", gray_png(8, 8, &[1; 64])), ("d", good)],
    );
    assert!(e.contains("input `c`") && e.contains("16×16"), "{e}");
}

/// `problem.channel`: a stack of two channels needs one, a channel the file does
/// not have is named, and the chosen one is read (tests/data/imagej_channels.tif:
/// channel 0 is `10 z + x`, channel 1 its complement).
#[test]
fn channels_are_chosen_with_problem_channel() {
    let stack = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/imagej_channels.tif")).unwrap();
    let with = |channel: &str| format!(r#"{{"problem": {{"type": "segmentation", "image": "input:s"{channel}}}}}"#);
    let e = image_error(&with(""), &[("s", stack.clone())]);
    assert!(e.starts_with("problem.channel: input `s`: is a stack of 2 channels") && e.contains("(0 to 1)"), "{e}");
    let e = image_error(&with(r#", "channel": 2"#), &[("s", stack.clone())]);
    assert!(e.starts_with("problem.channel:") && e.contains("channel 2 was asked for"), "{e}");
    let nifti = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ramp_nifti1.nii")).unwrap();
    let e = image_error(&with(r#", "channel": 1"#), &[("s", nifti.clone())]);
    assert!(e.starts_with("problem.channel: input `s`: is a volume of one channel"), "{e}");
    let e = image_error(&with(r#", "channel": 1"#), &[("s", nifti[..400].to_vec())]);
    assert!(e.starts_with("problem.image: input `s`:") && e.contains("truncated"), "{e}");
    let e = image_error(&with(r#", "channel": 1"#), &[("s", gray_png(16, 16, &(0..=255).collect::<Vec<u8>>()))]);
    assert!(e.starts_with("problem.channel: input `s`: has 1 channel (0 to 0)"), "{e}");
    let limits = shapeflow::imaging::ImageLimits::default();
    for (c, value) in [(0, 10.0 * 2.0 + 3.0), (1, 255.0 - (10.0 * 2.0 + 3.0))] {
        let plane = shapeflow::imaging::Plane { channel: Some(c), time_point: None };
        let g = shapeflow::imaging::decode_tiff_stack_plane("s", &stack, &limits, plane).unwrap();
        assert_eq!(g.dims, [6, 5, 4]);
        assert_eq!(g.values[g.index(3, 1, 2)], value);
    }
    // a colour image: the blue component instead of the luminance
    let mut rgb = Vec::new();
    let pixels: Vec<u8> = (0..64).flat_map(|i| [200, 100, i as u8 * 3]).collect();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut rgb),
        &pixels,
        8,
        8,
        image::ExtendedColorType::Rgb8,
    )
    .unwrap();
    let blue = shapeflow::imaging::decode_image_channel("c", &rgb, &limits, Some(2)).unwrap();
    // row 7 of the file is the grid's row 0
    assert_eq!(blue.values[blue.index(5, 0, 0)], (7 * 8 + 5) as f64 * 3.0);
    let e = shapeflow::imaging::decode_image_channel("c", &rgb, &limits, Some(3)).unwrap_err();
    assert!(e.subject == Subject::Channel && e.to_string().contains("has 3 channels (0 to 2)"), "{e}");
}

/// `problem.time_point`: a series of several time points needs one (with the
/// channel, for a stack of several channels), one it does not have is named,
/// and inputs of one time point have time point 0 only; a broken file is named
/// first (tests/data/imagej_series.tif, series_nifti1.nii.gz).
#[test]
fn time_points_are_chosen_with_problem_time_point() {
    let data = |name: &str| std::fs::read(format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let with = |extra: &str| format!(r#"{{"problem": {{"type": "segmentation", "image": "input:s"{extra}}}}}"#);
    let stack = data("imagej_series.tif");
    let e = image_error(&with(r#", "channel": 1"#), &[("s", stack.clone())]);
    assert!(e.starts_with("problem.time_point: input `s`: is a stack of 2 channels at 3 time points"), "{e}");
    assert!(e.contains("`problem.time_point` (0 to 2)"), "{e}");
    let e = image_error(&with(""), &[("s", stack.clone())]);
    assert!(e.starts_with("problem.channel:") && e.contains("and the time point"), "{e}");
    let e = image_error(&with(r#", "channel": 1, "time_point": 3"#), &[("s", stack)]);
    assert!(e.starts_with("problem.time_point:") && e.contains("time point 3 was asked for"), "{e}");
    let series = data("series_nifti1.nii.gz");
    let e = image_error(&with(""), &[("s", series.clone())]);
    assert!(e.starts_with("problem.time_point: input `s`: is a series of 3 time points"), "{e}");
    let e = image_error(&with(r#", "time_point": 7"#), &[("s", series)]);
    assert!(e.starts_with("problem.time_point:") && e.contains("time point 7 was asked for"), "{e}");
    let e = image_error(&with(r#", "time_point": 1"#), &[("s", data("ramp_nifti1.nii"))]);
    assert!(e.starts_with("problem.time_point: input `s`: is a series of 1 time point;"), "{e}");
    let e = image_error(&with(r#", "time_point": 1"#), &[("s", gray_png(16, 16, &(0..=255).collect::<Vec<u8>>()))]);
    assert!(e.starts_with("problem.time_point: input `s`: is an image of one time point"), "{e}");
    let e = image_error(&with(r#", "time_point": 1"#), &[("s", b"NRRD0004\ntype: float\n".to_vec())]);
    assert!(e.starts_with("problem.image: input `s`:"), "{e}");
    let e = image_error(&with(r#", "time_point": 1000001"#), &[("s", data("ramp_nifti1.nii"))]);
    assert!(e.starts_with("problem.time_point:"), "{e}");
}

fn p2(x: f64, y: f64) -> Point<2> {
    Point::<2>::new(x, y)
}

#[test]
fn mesh_errors_name_the_index() {
    let sq = vec![p2(0.0, 0.0), p2(1.0, 0.0), p2(1.0, 1.0), p2(0.0, 1.0)];
    let ok: Vec<[usize; 2]> = vec![[0, 1], [1, 2], [2, 3], [3, 0]];
    assert!(CurveMesh::new(sq.clone(), ok.clone()).is_ok());
    let mut nan = sq.clone();
    nan[2].x = f64::NAN;
    assert_eq!(CurveMesh::new(nan, ok.clone()), Err(MeshError::NonFinite { vertex: 2 }));
    assert_eq!(
        CurveMesh::new(sq.clone(), vec![[0, 1], [1, 2], [2, 7], [3, 0]]),
        Err(MeshError::IndexOutOfRange { element: 2, index: 7, count: 4 })
    );
    let mut dup = sq.clone();
    dup[1] = dup[0];
    assert_eq!(CurveMesh::new(dup, ok.clone()), Err(MeshError::Degenerate { element: 0 }));
    assert_eq!(
        CurveMesh::new(sq.clone(), vec![[0, 1], [1, 2], [2, 3], [3, 0], [0, 1]]),
        Err(MeshError::Duplicate { element: 4, other: 0 })
    );
    assert!(matches!(
        CurveMesh::new(sq.clone(), vec![[0, 1], [1, 2], [2, 3]]),
        Err(MeshError::CurveVertexDegree { vertex: 0, .. })
    ));
    let cw: Vec<[usize; 2]> = ok.iter().map(|e| [e[1], e[0]]).collect();
    assert!(matches!(CurveMesh::new(sq, cw), Err(MeshError::InwardOrientation { .. })));

    let s = icosphere([0.0; 3], 1.0, 1).unwrap();
    let mut tris = s.elements().to_vec();
    tris.pop();
    assert!(matches!(SurfaceMesh::new(s.positions().to_vec(), tris), Err(MeshError::OpenEdge { .. })));
    let inward: Vec<[usize; 3]> = s.elements().iter().map(|t| [t[0], t[2], t[1]]).collect();
    assert!(matches!(Mesh::new(s.positions().to_vec(), inward), Err(MeshError::InwardOrientation { .. })));
    // two spheres sharing one vertex: non-manifold vertex
    let a = icosphere([0.0; 3], 1.0, 1).unwrap();
    let mut pos = a.positions().to_vec();
    let shift = a.positions()[0] * 2.0;
    let n = pos.len();
    pos.extend(a.positions()[1..].iter().map(|p| p + shift));
    let map = |v: usize| if v == 0 { 0 } else { v + n - 1 };
    let mut tris = a.elements().to_vec();
    tris.extend(a.elements().iter().map(|t| [map(t[0]), map(t[1]), map(t[2])]));
    // reflect the copy's vertex 0 onto the original: use the shifted copy mirrored through vertex 0
    let pos2: Vec<Point<3>> =
        pos.iter().enumerate().map(|(i, p)| if i >= n { a.positions()[0] * 2.0 - (p - shift) } else { *p }).collect();
    let tris2: Vec<[usize; 3]> =
        tris.iter().enumerate().map(|(k, t)| if k >= a.num_elements() { [t[0], t[2], t[1]] } else { *t }).collect();
    assert_eq!(Mesh::new(pos2, tris2), Err(MeshError::NonManifoldVertex { vertex: 0 }));
    // bow tie polygon
    assert!(matches!(
        polygon(&[p2(0.0, 0.0), p2(1.0, 1.0), p2(1.0, 0.0), p2(0.0, 1.0)], None),
        Err(MeshError::SelfIntersection { .. })
    ));
    assert!(circle([0.0, 0.0], 1.0, 2).is_err());
}

#[test]
fn mesh_files_round_trip_and_errors_name_the_input() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    let m = read_mesh_file("tet", obj.as_bytes()).unwrap();
    assert!(matches!(m, AnyMesh::Surface(ref s) if (s.enclosed_measure() - 1.0 / 6.0).abs() < 1e-15));
    let off = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    assert_eq!(read_mesh_file("tet.off", off.as_bytes()).unwrap(), m);
    // counts in the header reserve nothing beyond the file (found by fuzzing: a face
    // count of 2e11 aborted the process on allocation)
    let huge = off.replace("4 4 0", "4 200000000000 0");
    let e = read_mesh_file("huge.off", huge.as_bytes()).unwrap_err().to_string();
    assert!(e.contains("huge.off") && e.contains("faces"), "{e}");
    let wide = off.replace("3 1 2 3\n", "5 1 2 3 0 1\n");
    let e = read_mesh_file("wide.off", wide.as_bytes()).unwrap_err().to_string();
    assert!(e.contains("wide.off") && e.contains("5 corners"), "{e}");
    // colours after a face's indices are ignored
    let coloured = off.replace("3 1 2 3\n", "3 1 2 3 0.5 0.25 1.0\n");
    assert_eq!(read_mesh_file("coloured.off", coloured.as_bytes()).unwrap(), m);
    // a face or polyline line cannot make the reader hold more indices than a mesh
    // may have vertices
    let long = format!("v 0 0 0\nf {}\n", "1 ".repeat(2_000_002));
    let e = read_mesh_file("long.obj", long.as_bytes()).unwrap_err().to_string();
    assert!(e.contains("long.obj") && e.contains("corners"), "{e}");
    let many = off.replace("4 4 0", "4 7999999 0");
    let e = read_mesh_file("many.off", many.as_bytes()).unwrap_err().to_string();
    assert!(e.contains("many.off") && e.contains("ends inside the face list"), "{e}");
    let curve = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nl 1 2 3 4 1\n";
    assert!(
        matches!(read_mesh_file("sq", curve.as_bytes()).unwrap(), AnyMesh::Curve(ref c) if (c.enclosed_measure() - 1.0).abs() < 1e-15)
    );
    let bad = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n";
    let err = read_mesh_file("broken.obj", bad.as_bytes()).unwrap_err();
    assert!(matches!(err, MeshFileError::Parse { line: 4, .. }), "{err}");
    assert!(err.to_string().contains("broken.obj"));
    let flipped = obj.replace("f 2 3 4", "f 2 4 3");
    let err = read_mesh_file("flipped", flipped.as_bytes()).unwrap_err();
    assert!(matches!(err, MeshFileError::Mesh { error: MeshError::InconsistentEdge { .. }, .. }), "{err}");
    assert!(matches!(read_mesh_file("junk", b"hello"), Err(MeshFileError::UnknownFormat { .. })));
    // binary STL of the same tetrahedron
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&4u32.to_le_bytes());
    let v = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for t in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
        stl.extend_from_slice(&[0u8; 12]);
        for i in t {
            for c in v[i] {
                stl.extend_from_slice(&c.to_le_bytes());
            }
        }
        stl.extend_from_slice(&[0u8; 2]);
    }
    assert!(matches!(read_mesh_file("tet.stl", &stl).unwrap(), AnyMesh::Surface(ref s) if s.num_vertices() == 4));
}
