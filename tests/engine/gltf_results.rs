//! glTF results: layout (docs/results.md), per-vertex fields with known values, and the
//! Khronos glTF-Validator (npm `gltf-validator`, installed by `npm ci`) reporting no
//! errors and no warnings on every file we write.

use crate::common::validate_gltf;
use serde_json::Value;
use shapeflow::flow::Checkpoint;
use shapeflow::jobs::{
    parse_spec, prepare, read_mesh_file, run_prepared, state_glb, states_glb, AnyMesh, PreparedJob, RunEvents,
};
use std::collections::HashMap;
use std::sync::atomic::AtomicBool;

#[derive(Default)]
struct Keep(Vec<Checkpoint>);
impl RunEvents for Keep {
    fn checkpoint(&mut self, c: &Checkpoint) {
        self.0.push(c.clone());
    }
}

fn run(spec: &str, inputs: &[(&str, Vec<u8>)]) -> (PreparedJob, Vec<Checkpoint>) {
    let files: HashMap<String, Vec<u8>> = inputs.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
    let job = prepare(parse_spec(spec).unwrap(), &files).unwrap();
    let mut keep = Keep::default();
    run_prepared(&job, None, &AtomicBool::new(false), &mut keep).unwrap();
    (job, keep.0)
}

/// The JSON chunk and the BIN chunk of a .glb.
fn parse_glb(g: &[u8]) -> (Value, &[u8]) {
    assert_eq!(&g[0..4], b"glTF");
    let jl = u32::from_le_bytes(g[12..16].try_into().unwrap()) as usize;
    let doc = serde_json::from_slice(&g[20..20 + jl]).unwrap();
    (doc, &g[28 + jl..])
}

/// The f32 values of accessor `a`.
fn floats(doc: &Value, bin: &[u8], a: usize) -> Vec<f32> {
    let acc = &doc["accessors"][a];
    let view = &doc["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
    let off = view["byteOffset"].as_u64().unwrap() as usize;
    let len = view["byteLength"].as_u64().unwrap() as usize;
    bin[off..off + len].chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect()
}

#[test]
fn curves_surfaces_and_segmentations_validate_with_the_right_fields() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let mut write = |name: &str, bytes: &[u8]| {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        files.push(p);
    };

    // two circles merging (several LINE_LOOP components in the early frames)
    let spec = std::fs::read_to_string("examples/merge_circles.json").unwrap();
    let (job, cps) = run(&spec, &[]);
    let evo = states_glb(&job, &cps).unwrap();
    let (doc, _) = parse_glb(&evo);
    // one root node per checkpoint (its lines), each with its filled region as a child
    let roots = doc["scenes"][0]["nodes"].as_array().unwrap();
    assert_eq!(roots.len(), cps.len());
    assert_eq!(doc["nodes"].as_array().unwrap().len(), 2 * cps.len());
    let lines =
        |root: &Value| &doc["meshes"][doc["nodes"][root.as_u64().unwrap() as usize]["mesh"].as_u64().unwrap() as usize];
    assert_eq!(lines(&roots[0])["primitives"].as_array().unwrap().len(), 2, "two components at the start");
    assert_eq!(lines(roots.last().unwrap())["primitives"].as_array().unwrap().len(), 1);
    assert!(roots
        .iter()
        .all(|r| doc["nodes"][r.as_u64().unwrap() as usize]["children"].as_array().is_some_and(|c| c.len() == 1)));
    let anim = &doc["animations"][0];
    assert_eq!(anim["samplers"][0]["interpolation"], "STEP");
    assert_eq!(anim["channels"].as_array().unwrap().len(), cps.len());
    let seconds = doc["extras"]["animation_seconds"].as_f64().unwrap();
    assert!((seconds - 0.2 * cps.len() as f64).abs() < 1e-6, "{seconds}");
    assert_eq!(doc["extras"]["problem"], "curvature_flow");
    write("merge_evolution.glb", &evo);
    write("merge_shape.glb", &state_glb(&job, cps.last().unwrap()));

    // a circle of radius 0.5 under curve-shortening: κ = 2, V = −κ = −2
    let (job, cps) = run(
        r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 0.5, "resolution": 64}, "flow": {"max_iterations": 1}}"#,
        &[],
    );
    let glb = state_glb(&job, &cps[0]);
    let (doc, bin) = parse_glb(&glb);
    let prim = &doc["meshes"][0]["primitives"][0];
    assert_eq!(prim["mode"], 2);
    let k = floats(&doc, bin, prim["attributes"]["_CURVATURE"].as_u64().unwrap() as usize);
    let v = floats(&doc, bin, prim["attributes"]["_NORMAL_VELOCITY"].as_u64().unwrap() as usize);
    assert_eq!(k.len(), 64);
    assert!(k.iter().all(|x| (x - 2.0).abs() < 1e-2), "{k:?}");
    assert!(v.iter().all(|x| (x + 2.0).abs() < 2e-2), "{v:?}");
    // the filled region (triangles of the 64-gon, its area) and the ribbon, in a
    // child node that the mesh readers skip
    let child = doc["nodes"][0]["children"][0].as_u64().unwrap() as usize;
    assert_eq!(doc["nodes"][child]["extras"]["shapeflow"], "display");
    let filled = &doc["meshes"][doc["nodes"][child]["mesh"].as_u64().unwrap() as usize]["primitives"];
    assert_eq!((filled[0]["mode"].as_u64(), filled[1]["mode"].as_u64()), (Some(4), Some(4)));
    assert_eq!(doc["accessors"][filled[0]["indices"].as_u64().unwrap() as usize]["count"], 3 * 62);
    assert_eq!(doc["accessors"][filled[1]["indices"].as_u64().unwrap() as usize]["count"], 6 * 64);
    assert!(filled[1]["attributes"]["COLOR_0"].is_number());
    // the colours: white at the median curvature (2), recorded with the node
    let colors = &doc["nodes"][0]["extras"]["colors"];
    assert!((colors["white"].as_f64().unwrap() - 2.0).abs() < 1e-2, "{colors}");
    assert_eq!(colors["field"], "_CURVATURE");
    // coloured by the normal velocity instead (V = −2 on this circle)
    let (job, cps) = run(
        r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 0.5, "resolution": 64},
            "flow": {"max_iterations": 1}, "output": {"color_by": "normal_velocity"}}"#,
        &[],
    );
    let (doc_v, _) = parse_glb(&state_glb(&job, &cps[0]));
    let colors = &doc_v["nodes"][0]["extras"]["colors"];
    assert_eq!(colors["field"], "_NORMAL_VELOCITY");
    assert!((colors["white"].as_f64().unwrap() + 2.0).abs() < 2e-2, "{colors}");
    write("circle.glb", &glb);
    // a result can start a new job: shape.glb read back as an uploaded initial mesh
    let AnyMesh::Curve(c) = read_mesh_file("circle.glb", &glb).unwrap() else { panic!("a curve") };
    assert_eq!(c.num_vertices(), 64);
    let area = 0.5 * 0.25 * 64.0 * (2.0 * std::f64::consts::PI / 64.0).sin(); // the inscribed 64-gon
    assert!((c.enclosed_measure() - area).abs() < 1e-5, "{}", c.enclosed_measure());

    // a sphere of radius 1 under mean curvature flow: κ = 2 (sum of principal curvatures)
    let (job, cps) = run(
        r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "sphere", "radius": 1.0, "resolution": 3}, "flow": {"max_iterations": 2}, "output": {"checkpoint_every": 1}}"#,
        &[],
    );
    let glb = state_glb(&job, &cps[0]);
    let (doc, bin) = parse_glb(&glb);
    let prim = &doc["meshes"][0]["primitives"][0];
    assert_eq!(prim["mode"], 4);
    assert!(prim["attributes"]["NORMAL"].is_number() && prim["indices"].is_number());
    let k = floats(&doc, bin, prim["attributes"]["_CURVATURE"].as_u64().unwrap() as usize);
    // (the pointwise discrete curvature of an icosphere varies with the valence)
    let mean = k.iter().sum::<f32>() / k.len() as f32;
    assert!((mean - 2.0).abs() < 0.05 && k.iter().all(|x| (x - 2.0).abs() < 0.35), "mean {mean}");
    write("sphere.glb", &glb);
    let AnyMesh::Surface(m) = read_mesh_file("sphere.glb", &glb).unwrap() else { panic!("a surface") };
    assert_eq!(m.num_vertices(), 642);
    assert!((m.enclosed_measure() - 4.0 / 3.0 * std::f64::consts::PI).abs() < 0.05, "{}", m.enclosed_measure());
    write("sphere_evolution.glb", &states_glb(&job, &cps).unwrap());

    // segmentation in 2D and 3D
    let (job, cps) = run(
        &std::fs::read_to_string("examples/segment_four.json").unwrap(),
        &[("image", std::fs::read("examples/data/four.png").unwrap())],
    );
    write("four_evolution.glb", &states_glb(&job, &cps).unwrap());
    let (job, cps) = run(
        &std::fs::read_to_string("examples/segment_balls.json").unwrap(),
        &[("volume", std::fs::read("examples/data/balls.nrrd").unwrap())],
    );
    write("balls.glb", &state_glb(&job, cps.last().unwrap()));
    write("balls_evolution.glb", &states_glb(&job, &cps).unwrap());

    // the stressed film: the periodic surface as one LINE_STRIP over a period
    let (job, cps) = run(
        r#"{"problem": {"type": "stressed_film", "length": 1.0, "gamma": 0.2},
            "initial": {"shape": "film", "height": 0.5, "amplitude": 0.05, "resolution": 32},
            "flow": {"end_time": 2e-4}, "output": {"checkpoint_every": 5}}"#,
        &[],
    );
    let glb = state_glb(&job, cps.last().unwrap());
    let (doc, bin) = parse_glb(&glb);
    let prim = &doc["meshes"][0]["primitives"][0];
    assert_eq!(prim["mode"], 3);
    let pos = floats(&doc, bin, prim["attributes"]["POSITION"].as_u64().unwrap() as usize);
    let n = pos.len() / 3;
    assert!((pos[3 * (n - 1)] - pos[0] - 1.0).abs() < 1e-6 && pos[3 * (n - 1) + 1] == pos[1], "closing vertex");
    assert!(pos[0] >= 0.0 && pos[0] < 0.05, "starts at the left wall: {}", pos[0]);
    // the film itself filled over the period, down to the substrate: its area
    let child = doc["nodes"][0]["children"][0].as_u64().unwrap() as usize;
    let filled = &doc["meshes"][doc["nodes"][child]["mesh"].as_u64().unwrap() as usize]["primitives"][0];
    let area = triangle_area(&doc, bin, filled);
    assert!((area - 0.5).abs() < 2e-3, "film area {area}");
    write("film.glb", &glb);
    write("film_evolution.glb", &states_glb(&job, &cps).unwrap());

    validate_gltf(&files);
}

/// The triangles of primitive `prim` (indexed `TRIANGLES`): their total area in the
/// plane z = const.
fn triangle_area(doc: &Value, bin: &[u8], prim: &Value) -> f64 {
    let p = floats(doc, bin, prim["attributes"]["POSITION"].as_u64().unwrap() as usize);
    let idx = &doc["accessors"][prim["indices"].as_u64().unwrap() as usize];
    let view = &doc["bufferViews"][idx["bufferView"].as_u64().unwrap() as usize];
    let off = view["byteOffset"].as_u64().unwrap() as usize;
    let tris: Vec<u32> = bin[off..off + view["byteLength"].as_u64().unwrap() as usize]
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    tris.chunks_exact(3)
        .map(|t| {
            let q = |k: usize| (p[3 * t[k] as usize] as f64, p[3 * t[k] as usize + 1] as f64);
            let (a, b, c) = (q(0), q(1), q(2));
            0.5 * ((b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1)).abs()
        })
        .sum()
}

/// `output.color_by: "problem_field"`: segmentation's edge indicator `H` and the
/// film's `|∇y|²` as attributes, coloured and named; refused for a problem without
/// a field. The shape-design domain (Σ and D) as its own node.
#[test]
fn problem_fields_and_the_design_domain_are_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let mut write = |name: &str, bytes: &[u8]| {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        files.push(p);
    };
    let values = |glb: &[u8], name: &str| {
        let (doc, bin) = parse_glb(glb);
        let prim = &doc["meshes"][0]["primitives"][0];
        assert_eq!(doc["nodes"][0]["extras"]["colors"]["field"], name);
        floats(&doc, bin, prim["attributes"][name].as_u64().unwrap() as usize)
    };

    // segmentation, geodesic model: H = 1/(1 + |∇I|²/k²) in (0, 1], low on the edges
    // the contour found; Chan–Vese: the normalized image, mid-way on the edges
    let spec = std::fs::read_to_string("examples/segment_four.json").unwrap();
    let mut spec: Value = serde_json::from_str(&spec).unwrap();
    spec["output"]["color_by"] = "problem_field".into();
    let image = [("image", std::fs::read("examples/data/four.png").unwrap())];
    let (job, cps) = run(&spec.to_string(), &image);
    let glb = state_glb(&job, cps.last().unwrap());
    let mut i = values(&glb, "_INTENSITY");
    i.sort_by(f32::total_cmp);
    assert!(i[i.len() / 2] > 0.2 && i[i.len() / 2] < 0.8, "median I on the found contour {}", i[i.len() / 2]);
    write("four_intensity.glb", &glb);
    spec["problem"]["model"] = "geodesic".into();
    let (job, cps) = run(&spec.to_string(), &image);
    let glb = state_glb(&job, cps.last().unwrap());
    let mut h = values(&glb, "_EDGE_INDICATOR");
    assert!(h.iter().all(|&x| x > 0.0 && x <= 1.0), "{h:?}");
    h.sort_by(f32::total_cmp);
    assert!(h[h.len() / 2] < 0.2, "median H on the found contour {}", h[h.len() / 2]);
    write("four_h.glb", &glb);

    // the film: |∇y|² ≥ 0, largest in the troughs (where the stress concentrates)
    let (job, cps) = run(
        r#"{"problem": {"type": "stressed_film", "length": 1.0, "gamma": 0.2},
            "initial": {"shape": "film", "height": 0.5, "amplitude": 0.05, "resolution": 32},
            "flow": {"end_time": 2e-4}, "output": {"checkpoint_every": 5, "color_by": "problem_field"}}"#,
        &[],
    );
    let glb = state_glb(&job, cps.last().unwrap());
    let e = values(&glb, "_ELASTIC_ENERGY_DENSITY");
    let (doc, bin) = parse_glb(&glb);
    let pos = floats(&doc, bin, doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap() as usize);
    assert!(e.iter().all(|&x| x >= 0.0) && e.iter().any(|&x| x > 0.0), "{e:?}");
    let lowest = (0..e.len()).min_by(|&a, &b| pos[3 * a + 1].total_cmp(&pos[3 * b + 1])).unwrap();
    let highest = (0..e.len()).max_by(|&a, &b| pos[3 * a + 1].total_cmp(&pos[3 * b + 1])).unwrap();
    assert!(e[lowest] > e[highest], "trough {} crest {}", e[lowest], e[highest]);
    write("film_energy_density.glb", &states_glb(&job, &cps).unwrap());

    // a problem without a field of its own: the spec is refused, naming the field
    let spec = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 0.5},
        "output": {"color_by": "problem_field"}}"#;
    let err = prepare(parse_spec(spec).unwrap(), &HashMap::new()).unwrap_err();
    assert_eq!(err.field, "output.color_by", "{err}");
    assert!(err.to_string().contains("curvature_flow"), "{err}");

    // shape design: Σ and D in a node of their own, D filled, not animated; a result
    // read back as a mesh is the curve alone
    let spec = std::fs::read_to_string("examples/design_ellipse.json").unwrap();
    let mut spec: Value = serde_json::from_str(&spec).unwrap();
    spec["flow"]["max_iterations"] = 3.into();
    spec["output"]["checkpoint_every"] = 1.into();
    let (job, cps) = run(&spec.to_string(), &[]);
    let glb = state_glb(&job, cps.last().unwrap());
    let (doc, bin) = parse_glb(&glb);
    let domain = doc["nodes"].as_array().unwrap().iter().find(|n| n["name"] == "domain: Σ and D").unwrap();
    assert_eq!(domain["extras"]["shapeflow"], "display");
    let prims = doc["meshes"][domain["mesh"].as_u64().unwrap() as usize]["primitives"].as_array().unwrap();
    assert_eq!(prims.iter().filter(|p| p["mode"] == 2).count(), 3, "Σ, and the two curves of ∂D");
    let control = prims.iter().find(|p| p["material"] == 3).unwrap();
    let (r_in, r_out) = (spec["problem"]["control"]["inner"]["radius"].as_f64().unwrap(), 2.5);
    assert_eq!(spec["problem"]["control"]["outer"]["radius"].as_f64(), Some(r_out));
    let annulus = std::f64::consts::PI * (r_out * r_out - r_in * r_in);
    let area = triangle_area(&doc, bin, control);
    assert!((area - annulus).abs() < 2e-3 * annulus, "D: {area} vs {annulus}");
    let AnyMesh::Curve(c) = read_mesh_file("design.glb", &glb).unwrap() else { panic!("a curve") };
    assert_eq!(c.num_vertices(), cps.last().unwrap().mesh.positions.len());
    write("design.glb", &glb);
    let evo = states_glb(&job, &cps).unwrap();
    let (doc, _) = parse_glb(&evo);
    assert_eq!(doc["scenes"][0]["nodes"].as_array().unwrap().len(), cps.len() + 1, "a root per frame, and the domain");
    assert_eq!(doc["animations"][0]["channels"].as_array().unwrap().len(), cps.len(), "the domain stays");
    write("design_evolution.glb", &evo);

    validate_gltf(&files);
}
