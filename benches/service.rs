//! Service latency: `POST /v1/jobs` and `GET /v1/jobs/{id}` (p50/p99) with 50
//! concurrent pollers while 2 workers compute, over real HTTP on 127.0.0.1; event
//! streams (100 SSE clients and 20 pollers); the service's overhead on a short job,
//! measured first on idle workers (wall time from POST to `successful`, or to the
//! `status` event, minus the engine time of the same job run in-process, and minus
//! what the CLI computes for it: the run, each checkpoint's fields, the result
//! files), then the same on the short job stopped after one step (a job's fixed
//! cost) and on jobs four and ten times longer with as many checkpoints; and
//! the latency of a claim with 100,000 finished jobs in the table, and the rate
//! of history batches the database takes from 1, 4 and 16 writers at once.
//! On a temporary SQLite file, or on PostgreSQL when `SHAPEFLOW_BENCH_DATABASE` is
//! a `postgres://` URL (an empty database: the bench fills it).
//! `cargo bench --bench service` (`-- short`: the overhead tables, the claim and the batch rate).

use shapeflow::jobs::{parse_spec, prepare, result_files, run_prepared, run_with_frames};
use shapeflow::service::store::ClaimPolicy;
use shapeflow::service::{Service, ServiceConfig};
use std::io::BufRead;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[path = "service/store_rates.rs"]
mod store_rates;

/// A job that keeps a worker busy for a while.
const BUSY: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 2000},
  "flow": {"tau": 1e-6, "end_time": 1.0, "max_iterations": 20000, "tolerance": 0}, "output": {"checkpoint_every": 100}}"#;
/// Runs of the short job (the engine's time varies by a third from run to run on
/// this machine; the medians of 11 are stable to a few per cent).
const RUNS: usize = 11;
/// A short job (about twenty milliseconds of engine time on this host).
const SHORT: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 256},
  "flow": {"tau": 1e-4, "end_time": 0.1, "max_iterations": 2000, "tolerance": 0}, "output": {"checkpoint_every": 100}}"#;

/// The short job stopped after its first step: what a job costs the service
/// whatever its run (submission, claim, the checkpoint, the result files, the
/// outcome and its event).
const ONE_STEP: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 256},
  "flow": {"tau": 1e-4, "end_time": 0.1, "max_iterations": 1, "tolerance": 0}, "output": {"checkpoint_every": 100}}"#;

/// The short job run four times longer, with as many checkpoints: about as long
/// as the short job's engine took on the host where the 10 % target was set
/// (about 80 ms).
const MEDIUM: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 256},
  "flow": {"tau": 2.5e-5, "end_time": 0.1, "max_iterations": 8000, "tolerance": 0}, "output": {"checkpoint_every": 400}}"#;

/// The short job run ten times longer, with as many checkpoints.
const LONGER: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 256},
  "flow": {"tau": 1e-5, "end_time": 0.1, "max_iterations": 20000, "tolerance": 0}, "output": {"checkpoint_every": 1000}}"#;

/// The engine's time on `spec` in-process, the CLI's work, and the service's from
/// POST to the end (polled, and told by the event stream): medians of `runs`,
/// printed as a table headed `what`.
fn overhead(addr: SocketAddr, spec: &str, runs: usize, what: &str) {
    let job = prepare(parse_spec(spec).unwrap(), &Default::default()).unwrap();
    let mut engine = Vec::new();
    let mut whole = Vec::new();
    let mut service_wall = Vec::new();
    let mut streamed = Vec::new();
    for _ in 0..runs {
        let t = Instant::now();
        run_prepared(&job, None, &AtomicBool::new(false), &mut ()).unwrap();
        engine.push(t.elapsed().as_secs_f64() * 1e3);
        // what the CLI computes for the same job: the run, each checkpoint's
        // frame (on a second thread while the run goes on), the result files
        let t = Instant::now();
        let (result, frames) = run_with_frames(&job, None, &AtomicBool::new(false), &mut ());
        result.unwrap();
        std::hint::black_box(result_files(&job, &frames));
        whole.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        let id = id_of(&http(addr, "POST", "/v1/jobs", Some(spec)).1);
        loop {
            let (_, body) = http(addr, "GET", &format!("/v1/jobs/{id}"), None);
            if body.contains("\"successful\"") {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        service_wall.push(t.elapsed().as_secs_f64() * 1e3);
        // the same, told by the job's event stream instead of polling
        let t = Instant::now();
        let id = id_of(&http(addr, "POST", "/v1/jobs", Some(spec)).1);
        until_status_event(addr, &id);
        streamed.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let (e, w) = (percentile(&mut engine, 0.5), percentile(&mut service_wall, 0.5));
    let sse = percentile(&mut streamed, 0.5);
    let c = percentile(&mut whole, 0.5);
    println!();
    println!("| {what} | median of {runs} |");
    println!("|---|---|");
    println!("| engine in-process | {e:.1} ms |");
    println!("| service: POST → successful (polled every ms) | {w:.1} ms |");
    println!("| overhead | {:.1} ms ({:.0} %) |", w - e, 100.0 * (w - e) / e);
    println!("| service: POST → status event on the job's SSE stream | {sse:.1} ms |");
    println!("| overhead | {:.1} ms ({:.0} %) |", sse - e, 100.0 * (sse - e) / e);
    println!("| in-process as the CLI: run, checkpoint fields, result files | {c:.1} ms |");
    println!("| service overhead beyond that, polled | {:.1} ms ({:.0} %) |", w - c, 100.0 * (w - c) / c);
    println!("| service overhead beyond that, SSE | {:.1} ms ({:.0} %) |", sse - c, 100.0 * (sse - c) / c);
}

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
    let database = std::env::var("SHAPEFLOW_BENCH_DATABASE")
        .unwrap_or_else(|_| dir.path().join("bench.db").to_string_lossy().into_owned());
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    // SHAPEFLOW_BENCH_OBJECT_STORE: an s3:// bucket instead of a temporary directory
    let object_store = std::env::var("SHAPEFLOW_BENCH_OBJECT_STORE").ok();
    let config = ServiceConfig {
        database: database.clone(),
        object_store,
        data_dir: dir.path().to_path_buf(),
        workers: 2,
        token: None,
        policy: ClaimPolicy::default(),
        // the service's own costs, apart from the job process's (benches/isolation.rs)
        isolation: shapeflow::service::isolation::Isolation::Thread,
        budgets: Default::default(),
        min_free_disk: shapeflow::service::MIN_FREE_DISK,
        faults: Vec::new(),
        cors_origins: Vec::new(),
        max_queued: None,
        retain: None,
    };
    let service = rt.block_on(Service::start_with(config)).unwrap();
    println!("backend: {}", service.state.store.backend());
    let listener = rt.block_on(tokio::net::TcpListener::bind("127.0.0.1:0")).unwrap();
    let addr = listener.local_addr().unwrap();
    let app = service.router();
    rt.spawn(async move { axum::serve(listener, app).await.unwrap() });

    // overhead on a short job, first, with idle workers and an empty database;
    // then on the same job stopped after one step (the fixed costs of a job's life
    // alone), and on jobs four and ten times longer with as many checkpoints (those
    // costs against longer runs)
    overhead(addr, SHORT, RUNS, "short job (1000 iterations, 256 vertices, checkpoints every 100)");
    overhead(addr, ONE_STEP, RUNS, "one-step job (the short job stopped after 1 iteration)");
    overhead(addr, MEDIUM, 7, "job of 4,000 iterations (256 vertices, checkpoints every 400)");
    overhead(addr, LONGER, 5, "longer job (10,000 iterations, 256 vertices, checkpoints every 1000)");
    // `-- short`: only the overhead tables, without the load after them
    if !std::env::args().any(|a| a == "short") {
        under_load(addr);
    }

    rt.block_on(service.stop());
    rt.block_on(store_rates::claims(&database, dir.path()));
}

/// POST and GET latency with 50 pollers, then 100 event streams and 20 pollers,
/// while two long jobs keep both workers busy.
fn under_load(addr: SocketAddr) {
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

    // 100 event streams and 20 pollers on the two busy jobs for 5 s
    let stop = Arc::new(AtomicBool::new(false));
    let streams: Vec<_> = (0..100)
        .map(|k| {
            let (stop, id) = (stop.clone(), busy[k % 2].clone());
            std::thread::spawn(move || follow(addr, &id, &stop))
        })
        .collect();
    let pollers: Vec<_> = (0..20)
        .map(|k| {
            let (stop, id) = (stop.clone(), busy[k % 2].clone());
            std::thread::spawn(move || {
                let mut lat = Vec::new();
                while !stop.load(Ordering::Relaxed) {
                    let t = Instant::now();
                    assert_eq!(http(addr, "GET", &format!("/v1/jobs/{id}"), None).0, 200);
                    lat.push(t.elapsed().as_secs_f64() * 1e3);
                }
                lat
            })
        })
        .collect();
    std::thread::sleep(Duration::from_secs(5));
    stop.store(true, Ordering::Relaxed);
    let mut polls: Vec<f64> = pollers.into_iter().flat_map(|h| h.join().unwrap()).collect();
    let followed: Vec<(f64, usize, f64)> = streams.into_iter().map(|h| h.join().unwrap()).collect();
    let mut first: Vec<f64> = followed.iter().map(|f| f.0).collect();
    let mut gaps: Vec<f64> = followed.iter().map(|f| f.2).collect();
    let events: usize = followed.iter().map(|f| f.1).sum();
    println!();
    println!("| 100 SSE clients, 20 pollers, 2 busy workers, 5 s | count | p50 | p99 |");
    println!("|---|---|---|---|");
    let n = polls.len();
    println!(
        "| GET /v1/jobs/{{id}} | {n} | {:.2} ms | {:.2} ms |",
        percentile(&mut polls, 0.5),
        percentile(&mut polls, 0.99)
    );
    println!(
        "| SSE: connect → first event (the history so far) | 100 | {:.2} ms | {:.2} ms |",
        percentile(&mut first, 0.5),
        percentile(&mut first, 0.99)
    );
    println!(
        "| SSE: longest wait between events, per client | 100 | {:.1} ms | {:.1} ms |",
        percentile(&mut gaps, 0.5),
        percentile(&mut gaps, 0.99)
    );
    println!("| SSE events delivered | {events} | | |");
    for id in &busy {
        http(addr, "POST", &format!("/v1/jobs/{id}/cancel"), None);
    }
    std::thread::sleep(Duration::from_millis(500));
}

/// Read the job's event stream until its `status` event.
fn until_status_event(addr: SocketAddr, id: &str) {
    let mut s = TcpStream::connect(addr).unwrap();
    write!(s, "GET /v1/jobs/{id}/events HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n").unwrap();
    let mut lines = std::io::BufReader::new(s).lines();
    while let Some(Ok(line)) = lines.next() {
        if line.starts_with("event: status") {
            return;
        }
    }
    panic!("the stream of {id} ended without a status event");
}

/// Follow a job's event stream until `stop`: ms to the first event, the number of
/// events, and the longest wait between two events (ms).
fn follow(addr: SocketAddr, id: &str, stop: &AtomicBool) -> (f64, usize, f64) {
    let t = Instant::now();
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(200))).unwrap();
    write!(s, "GET /v1/jobs/{id}/events HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n").unwrap();
    let mut reader = std::io::BufReader::new(s);
    let (mut first, mut count, mut longest, mut last) = (None, 0, 0.0f64, Instant::now());
    let mut line = String::new();
    while !stop.load(Ordering::Relaxed) {
        line.clear();
        match reader.read_line(&mut line) {
            Ok(0) => break,
            Ok(_) if line.starts_with("event: progress") => {
                first.get_or_insert(t.elapsed().as_secs_f64() * 1e3);
                if count > 0 {
                    longest = longest.max(last.elapsed().as_secs_f64() * 1e3);
                }
                last = Instant::now();
                count += 1;
            }
            _ => {}
        }
    }
    (first.unwrap_or(f64::NAN), count, longest)
}
