//! Serving the router over HTTP/1.1 so that slow and greedy clients cannot hold
//! the service (docs/operations.md, "HTTP limits"): hyper's own header timeout
//! (which also closes keep-alive connections idle for as long), a minimum rate
//! for request bodies ([`MinRate`]), and a cap on open connections whose last
//! [`HttpLimits::reserve`] serve only `/healthz` and `/readyz`. What a
//! reverse proxy (nginx's `client_header_timeout`, `client_body_timeout`,
//! `limit_conn`) would give, for a service that often runs without one.

use axum::extract::Request;
use axum::http::{header, HeaderValue};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use axum::Router;
use hyper_util::rt::{TokioIo, TokioTimer};
use std::future::Future;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tower::ServiceExt;

/// What a client may take of the service.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HttpLimits {
    /// Time to send a request's headers, and to start the next request on a
    /// kept-alive connection; the connection is closed after it.
    pub header_timeout: Duration,
    /// A body must arrive at this many bytes a second on average, after
    /// [`HttpLimits::body_grace`]; slower, the request ends with 408.
    pub body_min_rate: u64,
    pub body_grace: Duration,
    /// Open connections at most; beyond, new ones are closed at once.
    pub max_connections: usize,
    /// Of [`HttpLimits::max_connections`], the last ones serve only `/healthz`
    /// and `/readyz` (other routes answer 503 and close); they must send their
    /// request within [`RESERVE_HEADER_TIMEOUT`].
    pub reserve: usize,
}

impl Default for HttpLimits {
    fn default() -> Self {
        HttpLimits {
            header_timeout: Duration::from_secs(10),
            body_min_rate: 1024,
            body_grace: Duration::from_secs(10),
            max_connections: 1024,
            reserve: 32,
        }
    }
}

/// The header timeout of a connection of the reserve.
pub const RESERVE_HEADER_TIMEOUT: Duration = Duration::from_secs(1);

/// Whether the connection of a request was opened with the service crowded
/// (among the last [`HttpLimits::reserve`] connections).
#[derive(Debug, Clone, Copy)]
pub struct Crowded(pub bool);

/// Serve `app` on `listener` under `limits` until `shutdown` completes, then let
/// the open connections finish (at most `drain` long).
pub async fn serve(
    listener: tokio::net::TcpListener,
    app: Router,
    limits: HttpLimits,
    shutdown: impl Future<Output = ()>,
    drain: Duration,
) -> std::io::Result<()> {
    let app = app.layer(axum::middleware::from_fn(crowded)).layer(axum::middleware::from_fn_with_state(
        limits,
        |axum::extract::State(limits): axum::extract::State<HttpLimits>, req: Request, next: Next| async move {
            let (rate, grace) = (limits.body_min_rate, limits.body_grace);
            let req = req.map(|body| axum::body::Body::new(super::min_rate::MinRate::new(body, rate, grace)));
            next.run(req).await
        },
    ));
    let open = Arc::new(AtomicUsize::new(0));
    let graceful = hyper_util::server::graceful::GracefulShutdown::new();
    let mut builder = hyper::server::conn::http1::Builder::new();
    builder.timer(TokioTimer::new()).header_read_timeout(limits.header_timeout).keep_alive(true);
    // a connection of the reserve must ask at once (and is closed after its
    // answer), so that idle connections do not keep the reserve from the health checks
    let mut reserved = builder.clone();
    reserved.header_read_timeout(RESERVE_HEADER_TIMEOUT).keep_alive(false);
    let mut shutdown = std::pin::pin!(shutdown);
    loop {
        let (stream, _) = tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok(a) => a,
                Err(e) => {
                    // out of file descriptors, a connection reset before accept: go on
                    tracing::warn!("cannot accept a connection: {e}");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
            _ = &mut shutdown => break,
        };
        let count = open.fetch_add(1, Ordering::AcqRel) + 1;
        let guard = Open(open.clone());
        if count > limits.max_connections {
            drop(stream);
            continue;
        }
        let is_crowded = count > limits.max_connections.saturating_sub(limits.reserve);
        let service = app.clone().map_request(move |mut req: Request<hyper::body::Incoming>| {
            req.extensions_mut().insert(Crowded(is_crowded));
            req
        });
        let builder = if is_crowded { &reserved } else { &builder };
        let conn =
            builder.serve_connection(TokioIo::new(stream), hyper_util::service::TowerToHyperService::new(service));
        let conn = graceful.watch(conn);
        tokio::spawn(async move {
            let _guard = guard;
            if let Err(e) = conn.await {
                tracing::debug!("a connection ended: {e}");
            }
        });
    }
    drop(listener);
    tokio::select! {
        _ = graceful.shutdown() => {}
        _ = tokio::time::sleep(drain) => tracing::info!("open connections closed after {drain:?}"),
    }
    Ok(())
}

/// One open connection, counted until it ends.
struct Open(Arc<AtomicUsize>);

impl Drop for Open {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

/// On a connection opened crowded, only the health routes are served.
async fn crowded(req: Request, next: Next) -> Response {
    let crowded = req.extensions().get::<Crowded>().is_some_and(|c| c.0);
    if crowded && !matches!(req.uri().path(), "/healthz" | "/readyz") {
        let mut response = super::ApiError::Busy {
            detail: "the service has as many connections open as it takes; try again".into(),
            retry_after: 1,
        }
        .into_response();
        response.headers_mut().insert(header::CONNECTION, HeaderValue::from_static("close"));
        return response;
    }
    next.run(req).await
}

/// The status of `GET path` on `addr` (HTTP/1.1, no body read): the container
/// health check (`shapeflow health`), which needs no curl in the image.
pub fn probe(addr: &str, path: &str, timeout: Duration) -> std::io::Result<u16> {
    use std::io::{Read, Write};
    use std::net::ToSocketAddrs;
    let target = addr.to_socket_addrs()?.next().ok_or_else(|| std::io::Error::other(format!("no address {addr}")))?;
    let mut stream = std::net::TcpStream::connect_timeout(&target, timeout)?;
    stream.set_read_timeout(Some(timeout))?;
    stream.set_write_timeout(Some(timeout))?;
    write!(stream, "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n")?;
    let mut head = [0u8; 12];
    stream.read_exact(&mut head)?;
    let text = String::from_utf8_lossy(&head);
    text.get(9..12).and_then(|s| s.parse().ok()).ok_or_else(|| std::io::Error::other(format!("not HTTP: {text:?}")))
}
