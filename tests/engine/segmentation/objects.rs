//! Several objects found from one enclosing circle.

use super::*;

fn nearest(centres: &[[f64; 2]], x: f64, y: f64) -> usize {
    (0..centres.len())
        .min_by(|&a, &b| {
            let d = |c: [f64; 2]| (c[0] - x).hypot(c[1] - y);
            d(centres[a]).total_cmp(&d(centres[b]))
        })
        .unwrap()
}

/// Paper Figure 2: one enclosing circle splits into one curve per object.
#[test]
fn four_objects_from_one_circle() {
    let centres = [[36.0, 36.0], [92.0, 38.0], [34.0, 90.0], [90.0, 92.0]];
    let inside = move |x: f64, y: f64| {
        let k = nearest(&centres, x, y);
        let (dx, dy) = (x - centres[k][0], y - centres[k][1]);
        match k {
            0 => dx.hypot(dy) < 16.0,
            1 => dx.abs() < 14.0 && dy.abs() < 12.0,
            2 => (dx / 18.0).powi(2) + (dy / 11.0).powi(2) < 1.0,
            _ => dx.abs() + dy.abs() < 18.0,
        }
    };
    let p = picture(128, 128, 10.0, 11, inside);
    let spec = r#"{"initial": {"shape": "inscribed"}, "problem": {"type": "segmentation", "image": "input:image", "model": "geodesic", "lambda": 40}, "flow": {"max_iterations": 600}}"#;
    let (job, out) = run(spec, &[("image", png_gray8(&p))]);
    let m = mask(job.image.as_deref().unwrap(), &result_state(&job, &out.last).mesh);
    let cycles = out.last.mesh.to_mesh::<2>().unwrap().num_components();
    let mut scores = Vec::new();
    for k in 0..4 {
        let (mut both, mut a, mut b) = (0, 0, 0);
        for r in 0..128 {
            for c in 0..128 {
                if nearest(&centres, c as f64 + 0.5, r as f64 + 0.5) != k {
                    continue;
                }
                let got = m[c + 128 * (127 - r)];
                let want = p.truth[c + 128 * r];
                both += (got && want) as usize;
                a += got as usize;
                b += want as usize;
            }
        }
        scores.push(2.0 * both as f64 / (a + b) as f64);
    }
    eprintln!("{:?} after {} iterations: {cycles} components, dice {scores:?}", out.stop, out.last.iteration);
    assert_eq!(cycles, 4);
    assert!(scores.iter().all(|&d| d >= 0.95), "{scores:?}");
}
