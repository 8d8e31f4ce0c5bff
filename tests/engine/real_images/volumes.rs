//! Volumes: NRRD, NIfTI and TIFF stacks, touching objects in 3D.

use super::*;
use shapeflow::flow::Checkpoint;

/// Two overlapping balls (examples/data/balls.nrrd: radius 8.5, centres 15 apart,
/// 48³) at defaults: the threshold's surface is split at the neck, and the two
/// objects keep the union's volume. The surface's edges are kept between half
/// a voxel and one voxel, after a coarse start on edges of ¾ voxel to two:
/// its checkpoints say so, and one of them resumes in it to the same end.
#[test]
fn two_overlapping_balls_are_two_objects() {
    let inputs: HashMap<String, Vec<u8>> =
        [("image".to_string(), include_bytes!("../../../examples/data/balls.nrrd").to_vec())].into();
    let every_step =
        r#"{"problem": {"type": "segmentation", "image": "input:image"}, "output": {"checkpoint_every": 1}}"#;
    let job = prepare(parse_spec(every_step).unwrap(), &inputs).unwrap();
    let sizes = job.surface_manager.unwrap().params;
    let voxel = 1.0 / 48.0;
    assert!(sizes.h_max <= voxel && sizes.h_min >= 0.5 * voxel, "{sizes:?}");
    let coarse = job.coarse_manager.expect("a coarse start").params;
    assert_eq!((coarse.h_min, coarse.h_max), (1.5 * sizes.h_min, 2.0 * sizes.h_max));
    // a surface's length term weighs half a curve's (its mean curvature sums two)
    let setup = job.segmentation.as_ref().unwrap();
    assert_eq!(setup.mu, shapeflow::jobs::default_mu(setup.noise) / 2.0);
    // an h_min the spec gives stays, and h_max keeps at least twice it; the sizes
    // given, or the coarse start turned off, the run has no coarse start
    let with = |mesh: &str| {
        let spec = format!(r#"{{"problem": {{"type": "segmentation", "image": "input:image"}}, "mesh": {mesh}}}"#);
        prepare(parse_spec(&spec).unwrap(), &inputs).unwrap()
    };
    let given = with(r#"{"h_min": 0.012}"#);
    let other = given.surface_manager.unwrap().params;
    assert!(other.h_min == 0.012 && other.h_max >= 0.024, "{other:?}");
    assert!(given.coarse_manager.is_none());
    assert!(with(r#"{"coarse_start": false}"#).coarse_manager.is_none());
    assert!(with(r#"{"adapt": false}"#).coarse_manager.is_none());
    let timed =
        r#"{"problem": {"type": "segmentation", "image": "input:image"}, "flow": {"end_time": 1, "tolerance": 1e-5}}"#;
    assert!(prepare(parse_spec(timed).unwrap(), &inputs).unwrap().coarse_manager.is_none());

    let mut cps: Vec<Checkpoint> = Vec::new();
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut cps).unwrap();
    let img = job.image.as_deref().unwrap();
    let (_, rows) = objects(img, &result_state(&job, &out.last).mesh);
    let volume: f64 = rows.iter().map(|r| r.size).sum();
    let (r, d) = (8.5f64, 15.0f64);
    let lens = std::f64::consts::PI * (2.0 * r - d).powi(2) * (d * d + 4.0 * d * r) / (12.0 * d);
    let exact = 2.0 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) - lens;
    // the coarse start: the first checkpoints, then none; its edges longer than the end's
    let switch = cps.iter().position(|c| !c.coarse).expect("the run goes on at the default sizes");
    let last_coarse = &cps[switch - 1];
    let (e_coarse, e_end) = (mean_edge(last_coarse), mean_edge(&out.last));
    eprintln!(
        "balls: {} objects, volume {volume:.1} (exact {exact:.1}); coarse until iteration {} (mean edge {:.2} voxels), \
         converged after {} (mean edge {:.2} voxels)",
        rows.len(),
        last_coarse.iteration,
        e_coarse / voxel,
        out.last.iteration,
        e_end / voxel
    );
    assert_eq!(rows.len(), 2);
    assert!((volume / exact - 1.0).abs() < 0.05, "{volume} {exact}");
    assert!(cps[..switch].iter().all(|c| c.coarse) && cps[switch..].iter().all(|c| !c.coarse));
    assert!(switch > 1 && !out.last.coarse && out.last.iteration > last_coarse.iteration);
    // within their documented ranges: ¾ voxel to two at the start, ½ to one at the end
    assert!(e_coarse > e_end && (0.75 * voxel..=2.0 * voxel).contains(&e_coarse), "{e_coarse} {e_end}");
    assert!((0.5 * voxel..=voxel).contains(&e_end), "{e_coarse} {e_end}");
    // a checkpoint of the coarse start resumes in it and ends where the run did
    let resumed = run_prepared(&job, Some(&cps[switch / 2]), &AtomicBool::new(false), &mut ()).unwrap();
    assert_eq!((resumed.stop, resumed.last.iteration), (out.stop, out.last.iteration));
    assert!((resumed.last.energy / out.last.energy - 1.0).abs() < 1e-9, "{} {}", resumed.last.energy, out.last.energy);
}

/// The mean edge length of a checkpoint's surface.
fn mean_edge(c: &Checkpoint) -> f64 {
    shapeflow::geometry::edge_statistics(&c.mesh.to_mesh::<3>().unwrap()).0
}

/// A NIfTI-1 volume (gzip, float32) with slices twice as far apart as its pixels:
/// resampled to cubic voxels (40³), two overlapping balls of radius 8 and centres
/// 13 apart are two objects with the union's volume; the same volume as a
/// multi-page TIFF stack of 16-bit pages gives the same objects. Both report where
/// the resampled grid lies.
#[test]
fn an_anisotropic_nifti_volume_and_a_tiff_stack() {
    let (n, nz) = (40usize, 20usize);
    let (c1, c2, r) = ([14.0, 20.0, 20.0], [27.0, 20.0, 20.0], 8.0);
    let mut u = uniform(3);
    let mut noise = move || u() - 0.5;
    let mut voxels = Vec::with_capacity(n * n * nz);
    for k in 0..nz {
        for j in 0..n {
            for i in 0..n {
                // physical position: pixels 1 apart, slices 2 apart
                let p = [i as f64 + 0.5, j as f64 + 0.5, 2.0 * (k as f64 + 0.5)];
                let d = |c: [f64; 3]| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
                let inside = d(c1) < r || d(c2) < r;
                voxels.push(50.0 + if inside { 100.0 } else { 0.0 } + 10.0 * noise());
            }
        }
    }
    let mut header = vec![0u8; 352];
    header[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (o, v) in [(40, 3i16), (42, n as i16), (44, n as i16), (46, nz as i16), (70, 16), (72, 32)] {
        header[o..o + 2].copy_from_slice(&v.to_le_bytes());
    }
    for (o, v) in [(80, 1.0f32), (84, 1.0), (88, 2.0), (108, 352.0)] {
        header[o..o + 4].copy_from_slice(&v.to_le_bytes());
    }
    header[344..348].copy_from_slice(b"n+1\0");
    header.extend(voxels.iter().flat_map(|v| (*v as f32).to_le_bytes()));
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    std::io::Write::write_all(&mut gz, &header).unwrap();
    let nifti = gz.finish().unwrap();

    let h = 2.0 * r - 13.0;
    let lens = std::f64::consts::PI * h * h * (4.0 * r - h) / 6.0;
    let exact = 2.0 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) - lens;
    let check = |bytes: Vec<u8>, what: &str| {
        let inputs: HashMap<String, Vec<u8>> = [("image".to_string(), bytes)].into();
        let job = prepare(parse_spec(DEFAULTS).unwrap(), &inputs).unwrap();
        let img = job.image.as_deref().unwrap();
        assert_eq!(img.dims, [40, 40, 40], "{what}");
        // the results' grid lies where the input's samples did: its first voxel
        // half a new voxel in from the input's edge
        let setup = job.segmentation.as_ref().unwrap();
        assert_eq!((setup.voxel_spacing, setup.voxel_origin), (Some([1.0; 3]), Some([0.0, 0.0, -0.5])), "{what}");
        assert_eq!(img.placement.axes, shapeflow::imaging::Placement::aligned([1.0; 3], [0.0; 3]).axes, "{what}");
        let out = run_prepared(&job, None, &AtomicBool::new(false), &mut ()).unwrap();
        let (_, rows) = objects(img, &result_state(&job, &out.last).mesh);
        let volume: f64 = rows.iter().map(|r| r.size).sum();
        eprintln!(
            "{what}: {:?} after {} iterations, {} objects, volume {volume:.1} (exact {exact:.1})",
            out.stop,
            out.last.iteration,
            rows.len()
        );
        assert_eq!(rows.len(), 2, "{what}");
        assert!((volume / exact - 1.0).abs() < 0.05, "{what}: {volume} {exact}");
    };
    check(nifti, "nifti");

    // the same samples as a TIFF stack, ImageJ spacing 2
    use tiff::encoder::{colortype::Gray16, TiffEncoder};
    let mut out = std::io::Cursor::new(Vec::new());
    let mut enc = TiffEncoder::new(&mut out).unwrap();
    for k in 0..nz {
        let mut image = enc.new_image::<Gray16>(n as u32, n as u32).unwrap();
        image.encoder().write_tag(tiff::tags::Tag::ImageDescription, "ImageJ=1.11a\nspacing=2\n").unwrap();
        // pages are stored top row first: flip rows to keep the same orientation
        let page: Vec<u16> = (0..n * n)
            .map(|q| {
                let (i, row) = (q % n, q / n);
                voxels[i + n * ((n - 1 - row) + n * k)].round().max(0.0) as u16
            })
            .collect();
        image.write_data(&page).unwrap();
    }
    check(out.into_inner(), "tiff stack");
}

/// A first step so long (λ_in 1000, no step control) that the image box's
/// constraint clamps the surface flat onto the box's faces: the flattened trial
/// is retried with a shorter step like a tangled one. Accepted, it had made the
/// next step's velocity non-finite, and the run failed.
#[test]
fn a_step_flattened_against_the_image_box_is_retried() {
    let spec = r#"{"problem": {"type": "segmentation", "image": "input:image", "lambda_in": 1000},
        "flow": {"step_control": 0}, "initial": {"shape": "seeds", "spacing": 30, "radius": 5}}"#;
    let inputs: HashMap<String, Vec<u8>> =
        [("image".to_string(), include_bytes!("../../../examples/data/balls.nrrd").to_vec())].into();
    let job = prepare(parse_spec(spec).unwrap(), &inputs).unwrap();
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut ());
    let out = out.unwrap_or_else(|f| panic!("the run failed: {}", f.error));
    eprintln!("{:?} after {} iterations", out.stop, out.last.iteration);
    assert!(out.last.iteration > 0);
}

/// Two touching pairs of balls (radii 8 : 7 and 8 : 6, overlapping by a voxel,
/// uniform noise of ±20 on a contrast of 110) in a 48 × 32 × 36 volume, at defaults, every
/// state kept: the four balls are four objects; the run converges (it ended
/// `tau_min` at the first contact of two objects when the intersection check
/// alone kept them apart); and no state has two triangles that meet (all
/// triangle pairs through the broad phase).
#[test]
fn touching_pairs_of_balls_in_a_volume_are_kept_apart() {
    let (nx, ny, nz) = (48usize, 32usize, 36usize);
    let pairs = [([12.0, 16.0, 9.0], 8.0, [26.0, 16.0, 9.0], 7.0), ([18.0, 16.0, 27.0], 8.0, [31.0, 16.0, 27.0], 6.0)];
    let balls: Vec<([f64; 3], f64)> = pairs.iter().flat_map(|&(a, ra, b, rb)| [(a, ra), (b, rb)]).collect();
    let nrrd = balls_nrrd([nx, ny, nz], &balls, 11);
    let spec = r#"{"problem": {"type": "segmentation", "image": "input:image"}, "output": {"checkpoint_every": 1}}"#;
    let inputs: HashMap<String, Vec<u8>> = [("image".to_string(), nrrd)].into();
    let job = prepare(parse_spec(spec).unwrap(), &inputs).unwrap();
    let mut states: Vec<Checkpoint> = Vec::new();
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut states).unwrap();
    let img = job.image.as_deref().unwrap();
    let (_, rows) = objects(img, &result_state(&job, &out.last).mesh);
    eprintln!(
        "{:?} after {} iterations, {} objects, surgeries {:?}",
        out.stop,
        out.last.iteration,
        rows.len(),
        out.last.surgeries
    );
    assert_eq!(rows.len(), 4);
    assert_eq!(out.stop, shapeflow::flow::StopReason::Converged);
    let surface = |c: &Checkpoint| {
        let x: Vec<shapeflow::geometry::Point<3>> =
            c.mesh.positions.iter().map(|p| shapeflow::geometry::Point::<3>::new(p[0], p[1], p[2])).collect();
        let t: Vec<[usize; 3]> = c.mesh.elements.iter().map(|e| [e[0], e[1], e[2]]).collect();
        (x, t)
    };
    for c in &states {
        let (x, t) = surface(c);
        let hits = shapeflow::geometry::surface_intersections(&x, &t, 1);
        assert!(hits.is_empty(), "iteration {}: triangles {hits:?} meet", c.iteration);
    }
}

/// One surface over two balls (radii 7 and 6 voxels, 22 apart, noisy): the
/// initial ellipsoid covers both, the flow draws it in onto them, its middle
/// thins into a neck and the neck parts during the run. The parting is a
/// recorded pinch surgery (between the first and the last iteration, two
/// components after it), and the two objects have their balls' volumes to 5 %
/// and centres to half a voxel; no accepted state intersects itself.
#[test]
fn one_surface_over_two_balls_splits_at_its_neck_during_the_run() {
    let (nx, ny, nz) = (52usize, 32usize, 32usize);
    let balls = [([13.0, 16.0, 16.0], 7.0), ([35.0, 16.5, 15.5], 6.0)];
    let nrrd = balls_nrrd([nx, ny, nz], &balls, 5);
    let spec = r#"{"problem": {"type": "segmentation", "image": "input:image"},
        "initial": {"shape": "ellipsoid", "center": [0.47, 0.31, 0.3], "semi_axes": [0.42, 0.2, 0.2]},
        "output": {"checkpoint_every": 1}}"#;
    let inputs: HashMap<String, Vec<u8>> = [("image".to_string(), nrrd)].into();
    let job = prepare(parse_spec(spec).unwrap(), &inputs).unwrap();
    let mut states: Vec<Checkpoint> = Vec::new();
    let out = run_prepared(&job, None, &AtomicBool::new(false), &mut states).unwrap();
    let img = job.image.as_deref().unwrap();
    let (_, rows) = objects(img, &result_state(&job, &out.last).mesh);
    eprintln!("{:?} after {} iterations, surgeries {:?}", out.stop, out.last.iteration, out.last.surgeries);
    assert_eq!(out.stop, shapeflow::flow::StopReason::Converged);
    let pinch = out.last.surgeries.iter().find(|s| s.event.kind == shapeflow::flow::SurgeryKind::Pinch);
    let pinch = pinch.expect("the neck's parting is recorded");
    assert!(pinch.iteration > 1 && pinch.iteration < out.last.iteration, "{pinch:?}");
    assert_eq!(pinch.event.components, 2);
    assert_eq!(rows.len(), 2, "{rows:?}");
    for (c, r) in balls {
        // the objects' centroids are in voxel indices (a voxel's centre at its index)
        let row = rows.iter().find(|row| (row.centroid[0] - (c[0] - 0.5)).abs() < 3.0).expect("an object at each ball");
        let volume = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        assert!((row.size - volume).abs() < 0.05 * volume, "ball of radius {r}: volume {} for {volume}", row.size);
        for a in 0..3 {
            assert!((row.centroid[a] - (c[a] - 0.5)).abs() < 0.5, "ball of radius {r}: centroid {:?}", row.centroid);
        }
    }
    for c in &states {
        let x: Vec<shapeflow::geometry::Point<3>> =
            c.mesh.positions.iter().map(|p| shapeflow::geometry::Point::<3>::new(p[0], p[1], p[2])).collect();
        let t: Vec<[usize; 3]> = c.mesh.elements.iter().map(|e| [e[0], e[1], e[2]]).collect();
        let hits = shapeflow::geometry::surface_intersections(&x, &t, 1);
        assert!(hits.is_empty(), "iteration {}: triangles {hits:?} meet", c.iteration);
    }
}

/// A raw uint8 NRRD volume of `dims` voxels: the union of `balls` (centre and
/// radius in voxels, a voxel's centre at `i + 0.5`) at 170 on a background of 60,
/// with uniform noise of ±20 drawn from `seed`.
fn balls_nrrd(dims: [usize; 3], balls: &[([f64; 3], f64)], seed: u64) -> Vec<u8> {
    let [nx, ny, nz] = dims;
    let mut u = uniform(seed);
    let mut nrrd =
        format!("NRRD0004\ntype: uint8\ndimension: 3\nsizes: {nx} {ny} {nz}\nencoding: raw\n\n").into_bytes();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = [i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5];
                let inside = balls.iter().any(|(c, r)| (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>() < r * r);
                nrrd.push((60.0 + if inside { 110.0 } else { 0.0 } + 40.0 * (u() - 0.5)).clamp(0.0, 255.0) as u8);
            }
        }
    }
    nrrd
}
