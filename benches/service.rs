//! Service latency: `POST /v1/jobs` and `GET /v1/jobs/{id}` (p50/p99) with 50
//! concurrent pollers while 2 workers compute, over real HTTP on 127.0.0.1 with a
//! temporary SQLite file; and the service's overhead on a short job (wall time from
//! POST to `successful` minus the engine time of the same job run in-process).
//! `cargo bench --bench service`.

use shapeflow::jobs::{parse_spec, prepare, run_prepared};
use shapeflow::service::Service;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A job that keeps a worker busy for a while.
const BUSY: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 2000},
  "flow": {"tau": 1e-6, "end_time": 1.0, "max_iterations": 20000, "tolerance": 0}, "output": {"checkpoint_every": 100}}"#;
/// A short job (about a hundred milliseconds of engine time).
const SHORT: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 256},
  "flow": {"tau": 1e-4, "end_time": 0.1, "max_iterations": 2000, "tolerance": 0}, "output": {"checkpoint_every": 100}}"#;

fn http(addr: SocketAddr, method: &str, path: &str, body: Option<&str>) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    let b = body.unwrap_or("");
    let req = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n{b}",
        b.len()
    );
    s.write_all(req.as_bytes()).unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    let (head, body) = out.split_once("\r\n\r\n").unwrap();
    (head.split_whitespace().nth(1).unwrap().parse().unwrap(), body.to_string())
}

fn id_of(body: &str) -> String {
    serde_json::from_str::<serde_json::Value>(body).unwrap()["id"].as_str().unwrap().to_string()
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn main() {
    shapeflow::tune_allocator();
    let dir = tempfile::tempdir().unwrap();
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let service = rt.block_on(Service::start(&dir.path().join("bench.db"), 2, None)).unwrap();
    let listener = rt.block_on(tokio::net::TcpListener::bind("127.0.0.1:0")).unwrap();
    let addr = listener.local_addr().unwrap();
    let app = service.router();
    rt.spawn(async move { axum::serve(listener, app).await.unwrap() });

    // keep both workers busy
    let busy: Vec<String> = (0..2).map(|_| id_of(&http(addr, "POST", "/v1/jobs", Some(BUSY)).1)).collect();
    std::thread::sleep(Duration::from_millis(300));

    // 50 pollers for 5 s
    let stop = Arc::new(AtomicBool::new(false));
    let pollers: Vec<_> = (0..50)
        .map(|k| {
            let (stop, id) = (stop.clone(), busy[k % 2].clone());
            std::thread::spawn(move || {
                let mut lat = Vec::new();
                while !stop.load(Ordering::Relaxed) {
                    let t = Instant::now();
                    let (s, _) = http(addr, "GET", &format!("/v1/jobs/{id}"), None);
                    assert_eq!(s, 200);
                    lat.push(t.elapsed().as_secs_f64() * 1e3);
                }
                lat
            })
        })
        .collect();
    // submissions while polling (each stored before 201; cancelled right away)
    let mut submit = Vec::new();
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(5) {
        let t = Instant::now();
        let (s, body) = http(addr, "POST", "/v1/jobs", Some(SHORT));
        submit.push(t.elapsed().as_secs_f64() * 1e3);
        assert_eq!(s, 201);
        http(addr, "POST", &format!("/v1/jobs/{}/cancel", id_of(&body)), None);
        std::thread::sleep(Duration::from_millis(20));
    }
    stop.store(true, Ordering::Relaxed);
    let mut polls: Vec<f64> = pollers.into_iter().flat_map(|h| h.join().unwrap()).collect();
    let n_polls = polls.len();
    println!("| request (50 pollers, 2 busy workers) | count | p50 | p99 |");
    println!("|---|---|---|---|");
    let n_submit = submit.len();
    println!(
        "| POST /v1/jobs | {n_submit} | {:.2} ms | {:.2} ms |",
        percentile(&mut submit, 0.5),
        percentile(&mut submit, 0.99)
    );
    println!(
        "| GET /v1/jobs/{{id}} | {n_polls} | {:.2} ms | {:.2} ms |",
        percentile(&mut polls, 0.5),
        percentile(&mut polls, 0.99)
    );
    for id in &busy {
        http(addr, "POST", &format!("/v1/jobs/{id}/cancel"), None);
    }
    std::thread::sleep(Duration::from_millis(500));

    // overhead on a short job with idle workers
    let job = prepare(parse_spec(SHORT).unwrap(), &Default::default()).unwrap();
    let mut engine = Vec::new();
    let mut service_wall = Vec::new();
    for _ in 0..5 {
        let t = Instant::now();
        run_prepared(&job, None, &AtomicBool::new(false), &mut ()).unwrap();
        engine.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        let id = id_of(&http(addr, "POST", "/v1/jobs", Some(SHORT)).1);
        loop {
            let (_, body) = http(addr, "GET", &format!("/v1/jobs/{id}"), None);
            if body.contains("\"successful\"") {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        service_wall.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let (e, w) = (percentile(&mut engine, 0.5), percentile(&mut service_wall, 0.5));
    println!();
    println!("| short job (1000 iterations, 256 vertices, checkpoints every 100) | median of 5 |");
    println!("|---|---|");
    println!("| engine in-process | {e:.1} ms |");
    println!("| service: POST → successful (polled every ms) | {w:.1} ms |");
    println!("| overhead | {:.1} ms ({:.0} %) |", w - e, 100.0 * (w - e) / e);
    rt.block_on(service.stop());
}
