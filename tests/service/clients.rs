//! Slow, greedy and foreign clients against real `shapeflow serve` processes
//! (docs/operations.md): half-sent headers, a stalled body, a multipart part
//! header without end, more connections than the service takes, and a page of
//! another site posting jobs.

use super::nodes::{Liveness, Node, STEADY};
use super::*;

/// Connections that send half a request header are closed by the server after
/// its header timeout while `/healthz` keeps answering; connections beyond the
/// service's limit are closed at once.
#[test]
fn half_sent_headers_and_too_many_connections_do_not_hold_the_service() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "1", "--max-connections", "400"], "");
    let live = Liveness::watch(node.addr);
    let start = Instant::now();
    let mut half: Vec<TcpStream> = (0..300)
        .map(|_| {
            let mut s = TcpStream::connect(node.addr).unwrap();
            s.write_all(b"GET /v1/jobs HTTP/1.1\r\nHost: x\r\nX-Half: ").unwrap();
            s
        })
        .collect();
    // idle ones besides (up to 340 of 400: the reserve of the last 32 is kept for
    // the health checks; its own timeout is checked by the flood below)
    let idle: Vec<TcpStream> = (0..40).map(|_| TcpStream::connect(node.addr).unwrap()).collect();
    for s in &mut half {
        s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
        let mut buf = [0u8; 256];
        // the end of the stream (or a reset): closed by the server
        let n = s.read(&mut buf).unwrap_or(0);
        let text = String::from_utf8_lossy(&buf[..n]).to_string();
        assert!(n == 0 || text.starts_with("HTTP/1.1 408"), "{text}");
    }
    let closed = start.elapsed();
    assert!(closed < Duration::from_secs(30), "the half-sent headers were closed after {closed:?}");
    assert!(closed >= Duration::from_secs(9), "closed after {closed:?}, before the header timeout of 10 s");
    assert!(live.slowest() < 1000, "/healthz took {} ms", live.slowest());
    drop((idle, live));

    // 500 at once: those beyond 400 are closed without a word
    let flood: Vec<TcpStream> = (0..500).map(|_| TcpStream::connect(node.addr).unwrap()).collect();
    let mut ended = 0;
    for mut s in flood {
        s.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
        let mut buf = [0u8; 16];
        ended += matches!(s.read(&mut buf), Ok(0)) as usize;
    }
    assert!(ended >= 100, "{ended} of 500 connections were closed at once");
    let (status, _) = http_json(node.addr, "GET", "/v1/jobs", None);
    assert_eq!(status, 200);
}

/// A body that stops arriving ends with 408 after the grace period; a multipart
/// part header without end is refused before 100 MB of it has been read.
#[test]
fn a_stalled_body_is_408_and_an_endless_part_header_is_refused_early() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "1", "--body-grace", "2"], "");
    let idle = node.memory("VmRSS");
    let mut s = TcpStream::connect(node.addr).unwrap();
    s.write_all(
        b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 1000\r\n\r\n{\"pro",
    )
    .unwrap();
    let t = Instant::now();
    let mut answer = String::new();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let _ = s.read_to_string(&mut answer);
    assert!(answer.starts_with("HTTP/1.1 408"), "{answer}");
    assert!(
        answer.contains("application/problem+json") && answer.contains("slower than 1024 bytes a second"),
        "{answer}"
    );
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());

    let mut s = TcpStream::connect(node.addr).unwrap();
    let head = "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: multipart/form-data; boundary=b\r\n\
                Transfer-Encoding: chunked\r\n\r\n";
    s.write_all(head.as_bytes()).unwrap();
    let chunk = |data: &[u8]| [format!("{:x}\r\n", data.len()).as_bytes(), data, b"\r\n"].concat();
    s.write_all(&chunk(b"--b\r\nContent-Disposition: form-data; name=\"spec\"\r\nX-Pad: ")).unwrap();
    let pad = chunk(&vec![b'a'; 1 << 20]);
    s.set_write_timeout(Some(Duration::from_secs(20))).unwrap();
    let mut sent = 0usize;
    while sent < 200 << 20 && s.write_all(&pad).is_ok() {
        sent += 1 << 20;
    }
    assert!(sent < 100 << 20, "{} MiB of part header were taken", sent >> 20);
    let mut answer = String::new();
    let _ = s.read_to_string(&mut answer);
    assert!(answer.is_empty() || answer.starts_with("HTTP/1.1 413") || answer.starts_with("HTTP/1.1 400"), "{answer}");
    let grown = node.memory("VmHWM").saturating_sub(idle);
    assert!(grown < 100 << 20, "the server grew by {} MiB", grown >> 20);
    assert_eq!(http(node.addr, "GET", "/healthz", None, "").0, 200);
}

/// A POST or DELETE from a page of another site is 403; the service's own pages
/// and the origins given with `--cors-origin` may, the latter with CORS headers.
#[test]
fn a_foreign_origin_cannot_change_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "1", "--cors-origin", "http://app.example"], "");
    let post = |origin: &str| {
        let extra = format!("Origin: {origin}\r\n");
        http(node.addr, "POST", "/v1/jobs", Some(("application/json", STEADY)), &extra)
    };
    let (status, head, body) = post("http://evil.example");
    assert_eq!(status, 403, "{body}");
    assert!(head.to_ascii_lowercase().contains("application/problem+json"), "{head}");
    assert!(body.contains("http://evil.example"), "{body}");
    assert_eq!(post("null").0, 403);
    let (status, _, body) = post(&format!("http://{}", node.addr));
    assert_eq!(status, 201, "{body}");
    let id: Value = serde_json::from_str(&body).unwrap();
    let (status, head, body) = post("http://app.example");
    assert_eq!(status, 201, "{body}");
    assert!(head.to_ascii_lowercase().contains("access-control-allow-origin: http://app.example"), "{head}");
    // no Origin (curl, scripts): allowed, and no CORS headers
    let (status, head, _) = http(node.addr, "GET", "/v1/jobs", None, "");
    assert_eq!(status, 200);
    assert!(!head.to_ascii_lowercase().contains("access-control-allow"), "{head}");
    let path = format!("/v1/jobs/{}", id["id"].as_str().unwrap());
    node.wait_final(id["id"].as_str().unwrap());
    assert_eq!(http(node.addr, "DELETE", &path, None, "Origin: http://evil.example\r\n").0, 403);
    assert_eq!(http(node.addr, "DELETE", &path, None, "").0, 204);
}
