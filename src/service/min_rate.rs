//! A request body that must keep arriving: after a grace period, at least a
//! minimum number of bytes a second on average since the request's headers
//! came. A body that falls behind ends with [`SlowBody`], which the handlers
//! answer with 408 ([`is_slow_body`]). A large upload over a slow link still
//! works; a client that sends a byte now and then, or stops, does not hold the
//! service.

use axum::body::{Body, Bytes};
use http_body::{Frame, SizeHint};
use std::future::Future;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::time::{Instant, Sleep};

/// Why a body was cut: it arrived slower than the minimum rate.
#[derive(Debug, thiserror::Error)]
#[error("the request body arrived slower than {rate} bytes a second (after {grace} s)")]
pub struct SlowBody {
    pub rate: u64,
    pub grace: u64,
}

/// Whether `e` (or what caused it) is a [`SlowBody`].
pub fn is_slow_body(e: &(dyn std::error::Error + 'static)) -> bool {
    let mut next = Some(e);
    while let Some(e) = next {
        if e.is::<SlowBody>() {
            return true;
        }
        next = e.source();
    }
    false
}

/// A body under a minimum rate (see the module).
pub struct MinRate {
    inner: Body,
    start: Instant,
    received: u64,
    /// Bytes a second, on average, once `grace` has passed.
    rate: u64,
    grace: Duration,
    /// When the bytes received so far fall behind the rate, if nothing more comes.
    due: Option<Pin<Box<Sleep>>>,
}

impl MinRate {
    pub fn new(inner: Body, rate: u64, grace: Duration) -> MinRate {
        MinRate { inner, start: Instant::now(), received: 0, rate, grace, due: None }
    }

    fn deadline(&self) -> Instant {
        let ahead = self.received as f64 / self.rate.max(1) as f64;
        self.start + self.grace + Duration::from_secs_f64(ahead.min(1e9))
    }
}

impl http_body::Body for MinRate {
    type Data = Bytes;
    type Error = axum::BoxError;

    fn poll_frame(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Result<Frame<Bytes>, Self::Error>>> {
        let this = &mut *self;
        match Pin::new(&mut this.inner).poll_frame(cx) {
            Poll::Ready(Some(Ok(frame))) => {
                this.received += frame.data_ref().map_or(0, |d| d.len() as u64);
                this.due = None;
                Poll::Ready(Some(Ok(frame)))
            }
            Poll::Ready(Some(Err(e))) => Poll::Ready(Some(Err(e.into()))),
            Poll::Ready(None) => Poll::Ready(None),
            Poll::Pending => {
                let deadline = this.deadline();
                let due = this.due.get_or_insert_with(|| Box::pin(tokio::time::sleep_until(deadline)));
                match due.as_mut().poll(cx) {
                    Poll::Ready(()) => {
                        Poll::Ready(Some(Err(Box::new(SlowBody { rate: this.rate, grace: this.grace.as_secs() }))))
                    }
                    Poll::Pending => Poll::Pending,
                }
            }
        }
    }

    fn is_end_stream(&self) -> bool {
        self.inner.is_end_stream()
    }

    fn size_hint(&self) -> SizeHint {
        self.inner.size_hint()
    }
}
