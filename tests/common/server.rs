//! A service on 127.0.0.1 over a temporary SQLite file, and plain HTTP/1.1
//! requests to it.
#![allow(dead_code)] // not every test binary uses every helper

use serde_json::Value;
use shapeflow::service::Service;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::{Duration, Instant};

pub struct Server {
    pub rt: tokio::runtime::Runtime,
    pub service: Option<Service>,
    pub addr: SocketAddr,
    server: tokio::task::JoinHandle<()>,
}

impl Server {
    pub fn start(db: &Path, workers: usize) -> Server {
        Self::start_with(db, workers, None)
    }

    pub fn start_with(db: &Path, workers: usize, token: Option<&str>) -> Server {
        let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
        let service = rt.block_on(Service::start(db, workers, token.map(String::from))).unwrap();
        let listener = rt.block_on(tokio::net::TcpListener::bind("127.0.0.1:0")).unwrap();
        let addr = listener.local_addr().unwrap();
        let app = service.router();
        let server = rt.spawn(async move {
            axum::serve(listener, app).await.unwrap();
        });
        Server { rt, service: Some(service), addr, server }
    }

    /// Graceful stop: workers checkpoint running jobs, which stay `running`.
    pub fn stop(mut self) {
        let service = self.service.take().unwrap();
        self.rt.block_on(service.stop());
        self.server.abort();
    }

    pub fn request(&self, method: &str, path: &str, body: Option<(&str, &str)>) -> (u16, String, String) {
        http(self.addr, method, path, body, "")
    }

    pub fn json(&self, method: &str, path: &str, body: Option<&str>) -> (u16, Value) {
        http_json(self.addr, method, path, body)
    }

    pub fn wait_for(&self, id: &str, pred: impl Fn(&Value) -> bool) -> Value {
        wait_for(self.addr, id, pred)
    }
}

/// One HTTP/1.1 request (`Connection: close`) with optional body and extra header
/// lines (each ending in `\r\n`): status, head, body (de-chunked).
pub fn http(
    addr: SocketAddr,
    method: &str,
    path: &str,
    body: Option<(&str, &str)>,
    headers: &str,
) -> (u16, String, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let mut req = format!("{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n{headers}");
    match body {
        Some((ctype, b)) => req += &format!("Content-Type: {ctype}\r\nContent-Length: {}\r\n\r\n{b}", b.len()),
        None => req += "Content-Length: 0\r\n\r\n",
    }
    s.write_all(req.as_bytes()).unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    let (head, body) = out.split_once("\r\n\r\n").unwrap();
    let status = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    let body =
        if head.to_ascii_lowercase().contains("transfer-encoding: chunked") { dechunk(body) } else { body.to_string() };
    (status, head.to_string(), body)
}

/// A multipart/form-data body of `(name, filename, bytes)` parts; returns the
/// content type (with its boundary) and the body.
pub fn multipart(parts: &[(&str, Option<&str>, &[u8])]) -> (String, Vec<u8>) {
    let boundary = "shapeflow-test-boundary-7d1f";
    let mut body = Vec::new();
    for (name, file, data) in parts {
        body.extend(format!("--{boundary}\r\n").bytes());
        match file {
            Some(f) => body.extend(
                format!("Content-Disposition: form-data; name=\"{name}\"; filename=\"{f}\"\r\nContent-Type: application/octet-stream\r\n\r\n").bytes(),
            ),
            None => body.extend(format!("Content-Disposition: form-data; name=\"{name}\"\r\n\r\n").bytes()),
        }
        body.extend_from_slice(data);
        body.extend(b"\r\n");
    }
    body.extend(format!("--{boundary}--\r\n").bytes());
    (format!("multipart/form-data; boundary={boundary}"), body)
}

/// POST a binary body; returns status, head and body text.
pub fn post_bytes(addr: SocketAddr, path: &str, ctype: &str, body: &[u8]) -> (u16, String, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let head = format!(
        "POST {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Type: {ctype}\r\nContent-Length: {}\r\n\r\n",
        body.len()
    );
    s.write_all(head.as_bytes()).unwrap();
    // the server may answer (413) before reading everything: ignore write errors
    let _ = s.write_all(body);
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out).to_string();
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    let status = head.split_whitespace().nth(1).and_then(|s| s.parse().ok()).unwrap_or(0);
    (status, head.to_string(), body.to_string())
}

/// GET `path` as bytes (for binary results; the server sends Content-Length).
pub fn download(addr: SocketAddr, path: &str) -> (u16, String, Vec<u8>) {
    download_with(addr, path, "")
}

/// [`download`] with extra header lines (each ending in `\r\n`).
pub fn download_with(addr: SocketAddr, path: &str, headers: &str) -> (u16, String, Vec<u8>) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let req = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n{headers}Content-Length: 0\r\n\r\n");
    s.write_all(req.as_bytes()).unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).unwrap();
    let split = out.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let head = String::from_utf8_lossy(&out[..split]).to_string();
    let status = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    let body = &out[split + 4..];
    let chunked = head.to_ascii_lowercase().contains("transfer-encoding: chunked");
    (status, head, if chunked { dechunk_bytes(body) } else { body.to_vec() })
}

pub fn http_json(addr: SocketAddr, method: &str, path: &str, body: Option<&str>) -> (u16, Value) {
    let (status, _, b) = http(addr, method, path, body.map(|b| ("application/json", b)), "");
    (status, serde_json::from_str(&b).unwrap_or(Value::Null))
}

/// Poll a job until `pred` holds (two minutes at most).
pub fn wait_for(addr: SocketAddr, id: &str, pred: impl Fn(&Value) -> bool) -> Value {
    let start = Instant::now();
    loop {
        let (_, j) = http_json(addr, "GET", &format!("/v1/jobs/{id}"), None);
        if pred(&j) {
            return j;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "timed out waiting: {j}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

pub fn dechunk(body: &str) -> String {
    String::from_utf8(dechunk_bytes(body.as_bytes())).unwrap()
}

/// The body of a chunked transfer.
pub fn dechunk_bytes(body: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut rest = body;
    while let Some(eol) = rest.windows(2).position(|w| w == b"\r\n") {
        let size = std::str::from_utf8(&rest[..eol]).unwrap_or("0");
        let n = usize::from_str_radix(size.trim(), 16).unwrap_or(0);
        if n == 0 {
            break;
        }
        let tail = &rest[eol + 2..];
        out.extend_from_slice(&tail[..n]);
        rest = &tail[n + 2..];
    }
    out
}
