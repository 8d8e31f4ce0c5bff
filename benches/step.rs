//! Time and memory per semi-implicit step (assembly + Schur solve) for curves and
//! icospheres and every scalar product, next to the floor: one faer sparse Cholesky
//! numeric factorization (symbolic part reused, AMD ordering) plus solve of `A + M` on the same mesh.
//!
//! `cargo bench --bench step` runs every case in a child process (so that the peak
//! resident memory, VmHWM, belongs to that case alone) and prints a Markdown table
//! plus the fitted exponents `time ∝ N^p`. `cargo bench --bench step -- quick` runs
//! the smaller sizes only. `cargo bench --bench step -- bending` compares the
//! `H^{-1}` curve step with and without a bending energy `ε/2 ∫ κ²` (ε = 2e-4,
//! τ = 1e-5, g = 1: the implicit `−εΔ_Γκ` and the third preconditioner factor).

use shapeflow::fem::{Matrices, Pattern, Weight};
use shapeflow::flow::{LinearSystem, ProductWeights, SemiImplicitStep, SolverKind, SparseCholesky};
use shapeflow::geometry::{circle, icosphere, Mesh};
use std::hint::black_box;

#[path = "common/mod.rs"]
mod common;
use common::{peak_rss_mib, time_it};

fn case<const D: usize>(mesh: &Mesh<D>, product: &str, bending: f64) -> f64 {
    let pattern = Pattern::new(mesh.num_vertices(), mesh.elements());
    let n = mesh.num_vertices();
    if product == "floor" {
        let m = Matrices::assemble(mesh, &pattern);
        let vals: Vec<f64> = m.stiffness.iter().zip(&m.mass).map(|(a, b)| a + b).collect();
        let sym = pattern.symbolic().as_ref();
        let mut chol = SparseCholesky::new(sym).unwrap();
        return time_it(0.5, || {
            chol.factorize(sym, &vals).unwrap();
            let mut x = vec![1.0; n];
            chol.solve_in_place(&mut x);
            black_box(x);
        });
    }
    let weights = match product {
        "l2" => ProductWeights::L2,
        "h1" => ProductWeights::H1 { alpha: Weight::Constant(1e-2), beta: Weight::Constant(1.0) },
        "h_minus_1" => ProductWeights::HMinus1,
        _ => unreachable!(),
    };
    let g = vec![1.0; n];
    let f = vec![0.0; n];
    let tau = if product == "h_minus_1" { 1e-5 } else { 1e-3 };
    let mut step = SemiImplicitStep::new(SolverKind::Lumped);
    let mut m = Matrices::assemble(mesh, &pattern);
    time_it(0.5, || {
        m.assemble_into(mesh, &pattern, false);
        let ax = m.stiffness_times_positions(mesh, &pattern);
        let sys = LinearSystem {
            mesh,
            pattern: &pattern,
            matrices: &m,
            ax: &ax,
            g: &g,
            f: &f,
            product: &weights,
            tau,
            bending,
            limits: None,
        };
        black_box(step.velocity(&sys).unwrap());
    })
}

const MESHES: [(&str, usize, bool); 7] = [
    ("curve", 1_000, true),
    ("curve", 10_000, true),
    ("curve", 100_000, false),
    ("icosphere", 4, true),
    ("icosphere", 5, true),
    ("icosphere", 6, false),
    ("icosphere", 7, false),
];
const PRODUCTS: [&str; 4] = ["floor", "l2", "h1", "h_minus_1"];

fn child(kind: &str, size: usize, product: &str) {
    let (secs, n) = if kind == "curve" {
        let m = circle([0.0, 0.0], 1.0, size).unwrap();
        (case(&m, product, 0.0), m.num_vertices())
    } else {
        let m = icosphere([0.0; 3], 1.0, size as u32).unwrap();
        (case(&m, product, 0.0), m.num_vertices())
    };
    println!("{kind} {n} {product} {secs} {}", peak_rss_mib());
}

fn main() {
    shapeflow::tune_allocator();
    let args: Vec<String> = std::env::args().collect();
    if let Some(pos) = args.iter().position(|a| a == "--case") {
        child(&args[pos + 1], args[pos + 2].parse().unwrap(), &args[pos + 3]);
        return;
    }
    if args.iter().any(|a| a == "bending") {
        println!("| curve vertices | H^-1 (ms) | H^-1 with bending (ms) | ratio |");
        println!("|---:|---:|---:|---:|");
        for n in [1_000, 10_000, 100_000] {
            let m = circle([0.0, 0.0], 1.0, n).unwrap();
            let (plain, bent) = (case(&m, "h_minus_1", 0.0), case(&m, "h_minus_1", 2e-4));
            println!("| {n} | {:.3} | {:.3} | {:.2} |", plain * 1e3, bent * 1e3, bent / plain);
        }
        return;
    }
    let quick = args.iter().any(|a| a == "quick");
    let exe = std::env::current_exe().unwrap();
    let mut rows: Vec<(String, usize, String, f64, f64)> = Vec::new();
    for (kind, size, small) in MESHES {
        if quick && !small {
            continue;
        }
        for product in PRODUCTS {
            let out =
                std::process::Command::new(&exe).args(["--case", kind, &size.to_string(), product]).output().unwrap();
            let line = String::from_utf8_lossy(&out.stdout);
            let p: Vec<&str> = line.split_whitespace().collect();
            if p.len() < 5 {
                eprintln!("case {kind} {size} {product} failed: {}", String::from_utf8_lossy(&out.stderr));
                continue;
            }
            let row = (
                p[0].to_string(),
                p[1].parse().unwrap(),
                p[2].to_string(),
                p[3].parse().unwrap(),
                p[4].parse().unwrap(),
            );
            eprintln!("{:?}", row);
            rows.push(row);
        }
    }
    println!("| mesh | vertices | floor (ms) | L2 (ms) | H1 (ms) | H^-1 (ms) | L2/floor | H1/floor | H^-1/floor | peak RSS floor / L2 / H1 / H^-1 (MiB) |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|");
    let mut keys: Vec<(String, usize)> = rows.iter().map(|r| (r.0.clone(), r.1)).collect();
    keys.dedup();
    for (kind, n) in &keys {
        let get = |p: &str| rows.iter().find(|r| &r.0 == kind && r.1 == *n && r.2 == p).map(|r| (r.3 * 1e3, r.4));
        let (fl, l2, h1, hm) = (get("floor"), get("l2"), get("h1"), get("h_minus_1"));
        let ms = |x: Option<(f64, f64)>| x.map_or("–".into(), |v| format!("{:.3}", v.0));
        let ratio = |x: Option<(f64, f64)>| match (x, fl) {
            (Some(a), Some(b)) => format!("{:.2}", a.0 / b.0),
            _ => "–".into(),
        };
        let mem = |x: Option<(f64, f64)>| x.map_or("–".into(), |v| format!("{:.0}", v.1));
        println!(
            "| {kind} | {n} | {} | {} | {} | {} | {} | {} | {} | {} / {} / {} / {} |",
            ms(fl),
            ms(l2),
            ms(h1),
            ms(hm),
            ratio(l2),
            ratio(h1),
            ratio(hm),
            mem(fl),
            mem(l2),
            mem(h1),
            mem(hm)
        );
    }
    println!();
    for kind in ["curve", "icosphere"] {
        for product in PRODUCTS {
            let pts: Vec<(f64, f64)> =
                rows.iter().filter(|r| r.0 == kind && r.2 == product).map(|r| ((r.1 as f64).ln(), r.3.ln())).collect();
            if pts.len() < 2 {
                continue;
            }
            let mx = pts.iter().map(|p| p.0).sum::<f64>() / pts.len() as f64;
            let my = pts.iter().map(|p| p.1).sum::<f64>() / pts.len() as f64;
            let slope = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
                / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
            println!("- {kind}, {product}: time ∝ N^{slope:.2}");
        }
    }
}
