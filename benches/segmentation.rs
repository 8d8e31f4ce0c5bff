//! End-to-end segmentation: decode → edge indicator → flow → mask, on synthetic
//! images with known masks (a noisy star in 2D, two touching balls in 3D), with the
//! Dice score of the result. `cargo bench --bench segmentation [-- quick]` (quick:
//! only the small sizes). The small sizes report the median of five runs after a
//! warm-up, the large ones a single run.

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};
use shapeflow::export::mask;
use shapeflow::jobs::{parse_spec, prepare, result_state, run_prepared};
use std::collections::HashMap;
use std::io::Write;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

struct Rng(u64);
impl Rng {
    fn normal(&mut self) -> f64 {
        let mut u = || {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        };
        let (a, b) = (u().max(1e-300), u());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

/// The star of the tests scaled to `n × n`; truth in grid order (rows from the bottom).
fn star_png(n: usize) -> (Vec<u8>, Vec<bool>) {
    let s = n as f64 / 128.0;
    let mut rng = Rng(7);
    let (mut gray, mut truth) = (Vec::new(), vec![false; n * n]);
    for r in 0..n {
        for c in 0..n {
            let (dx, dy) = (c as f64 + 0.5 - 64.0 * s, r as f64 + 0.5 - 64.0 * s);
            let t = dx.hypot(dy) < 34.0 * s * (1.0 + 0.3 * (5.0 * dy.atan2(dx)).cos());
            truth[c + n * (n - 1 - r)] = t;
            gray.push(((if t { 190.0 } else { 60.0 }) + 12.0 * rng.normal()).clamp(0.0, 255.0).round() as u8);
        }
    }
    let mut png = Vec::new();
    PngEncoder::new(&mut png).write_image(&gray, n as u32, n as u32, ExtendedColorType::L8).unwrap();
    (png, truth)
}

/// Two touching balls in `n³` (radius 0.18 n, centres 0.31 n apart), gzip NRRD.
fn balls_nrrd(n: usize) -> (Vec<u8>, Vec<bool>) {
    let f = n as f64;
    let (c1, c2, r) = ([0.345 * f, 0.5 * f, 0.5 * f], [0.655 * f, 0.5 * f, 0.5 * f], 0.18 * f);
    let mut rng = Rng(5);
    let (mut vox, mut truth) = (Vec::new(), Vec::new());
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = [i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5];
                let d = |c: [f64; 3]| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
                let t = d(c1) < r || d(c2) < r;
                truth.push(t);
                vox.push(((if t { 190.0 } else { 60.0 }) + 10.0 * rng.normal()).clamp(0.0, 255.0).round() as u8);
            }
        }
    }
    let mut out = format!("NRRD0004\ntype: uint8\ndimension: 3\nsizes: {n} {n} {n}\nencoding: gzip\n\n").into_bytes();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&vox).unwrap();
    out.extend(gz.finish().unwrap());
    (out, truth)
}

fn dice(a: &[bool], b: &[bool]) -> f64 {
    let both = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    2.0 * both as f64 / (a.iter().filter(|x| **x).count() + b.iter().filter(|x| **x).count()) as f64
}

fn main() {
    shapeflow::tune_allocator();
    let quick = std::env::args().any(|a| a == "quick");
    let mut cases: Vec<(String, Vec<u8>, Vec<bool>)> = Vec::new();
    for n in [100usize, 128, 1024] {
        if quick && n > 128 {
            continue;
        }
        let (bytes, truth) = star_png(n);
        cases.push((format!("{n}² star"), bytes, truth));
    }
    for n in [64usize, 128] {
        if quick && n > 64 {
            continue;
        }
        let (bytes, truth) = balls_nrrd(n);
        cases.push((format!("{n}³ balls"), bytes, truth));
    }
    println!("| image | iterations | vertices | decode+prepare | flow | refine+mask | total | Dice |");
    println!("|---|---|---|---|---|---|---|---|");
    let spec = parse_spec(
        r#"{"initial": {"shape": "inscribed"}, "problem": {"type": "segmentation", "image": "input:image", "model": "geodesic"}, "flow": {"max_iterations": 2000}}"#,
    )
    .unwrap();
    for (name, bytes, truth) in cases {
        let inputs: HashMap<String, Vec<u8>> = [("image".to_string(), bytes)].into();
        // the small sizes: the run with the median total of five (after one not
        // counted); the large ones once
        let small = name.starts_with("100²") || name.starts_with("128²") || name.starts_with("64³");
        let runs: Vec<_> = (0..if small { 6 } else { 1 })
            .map(|_| {
                let t0 = Instant::now();
                let job = prepare(spec.clone(), &inputs).unwrap();
                let t1 = Instant::now();
                let out = run_prepared(&job, None, &AtomicBool::new(false), &mut ()).unwrap();
                let t2 = Instant::now();
                // the mask the results serve: the contour refined onto the edges
                let m = mask(job.image.as_deref().unwrap(), &result_state(&job, &out.last).mesh);
                let t3 = Instant::now();
                (t0, t1, t2, t3, out, m)
            })
            .collect();
        let mut runs: Vec<_> = runs.into_iter().skip(usize::from(small)).collect();
        runs.sort_by_key(|r| r.3 - r.0);
        let (t0, t1, t2, t3, out, m) = &runs[runs.len() / 2];
        let ms = |a: &Instant, b: &Instant| (*b - *a).as_secs_f64() * 1e3;
        println!(
            "| {name} | {} | {} | {:.0} ms | {:.0} ms | {:.0} ms | {:.1} ms | {:.4} |",
            out.last.iteration,
            out.last.mesh.positions.len(),
            ms(t0, t1),
            ms(t1, t2),
            ms(t2, t3),
            ms(t0, t3),
            dice(m, &truth)
        );
    }
}
