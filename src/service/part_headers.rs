//! A multipart body whose part headers are bounded: after each boundary line the
//! headers must end (a blank line) within [`MAX_PART_HEADER`] bytes, or the body
//! fails with [`PartHeaderTooLong`]. The multipart reader keeps a part's headers
//! in memory until they end, so without this a header that never ends would
//! grow its buffer to the whole body's limit (and its capacity to twice that).

use axum::body::{Body, Bytes};
use http_body::{Frame, SizeHint};
use memchr::memmem;
use std::pin::Pin;
use std::task::{Context, Poll};

/// The most bytes a part's headers may take (far more than a name, a file name
/// and a content type need).
pub const MAX_PART_HEADER: usize = 64 << 10;

#[derive(Debug, thiserror::Error)]
#[error("a multipart part's headers are longer than {0} bytes")]
pub struct PartHeaderTooLong(pub usize);

/// The body, watched (see the module documentation).
pub struct PartHeaders {
    inner: Body,
    /// `\r\n--` and the boundary: where a part (and its headers) begins.
    delimiter: Vec<u8>,
    /// In a part's headers: how many bytes of them so far.
    in_header: Option<usize>,
    /// The last bytes seen, for a delimiter or a blank line split across frames.
    tail: Vec<u8>,
}

impl PartHeaders {
    pub fn new(inner: Body, boundary: &str) -> PartHeaders {
        // the first delimiter may open the body without its CRLF: counted as one
        let delimiter = format!("\r\n--{boundary}").into_bytes();
        PartHeaders { inner, delimiter, in_header: None, tail: b"\r\n".to_vec() }
    }

    /// Follow `data`; an error once a part's headers are too long.
    fn scan(&mut self, data: &[u8]) -> Result<(), PartHeaderTooLong> {
        let keep = self.delimiter.len().max(4);
        let mut window = std::mem::take(&mut self.tail);
        let start = window.len();
        window.extend_from_slice(data);
        let mut at = 0;
        loop {
            match self.in_header {
                None => match memmem::find(&window[at..], &self.delimiter) {
                    Some(i) => {
                        at += i + self.delimiter.len();
                        self.in_header = Some(0);
                    }
                    None => break,
                },
                Some(n) => match memmem::find(&window[at..], b"\r\n\r\n") {
                    Some(i) => {
                        at += i + 4;
                        self.in_header = None;
                    }
                    None => {
                        let n = n + window.len() - at.max(start.min(window.len()));
                        if n > MAX_PART_HEADER {
                            return Err(PartHeaderTooLong(MAX_PART_HEADER));
                        }
                        self.in_header = Some(n);
                        break;
                    }
                },
            }
        }
        let from = window.len().saturating_sub(keep).max(at.min(window.len()));
        self.tail = window[from..].to_vec();
        Ok(())
    }
}

impl http_body::Body for PartHeaders {
    type Data = Bytes;
    type Error = axum::BoxError;

    fn poll_frame(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Result<Frame<Bytes>, Self::Error>>> {
        let this = &mut *self;
        match Pin::new(&mut this.inner).poll_frame(cx) {
            Poll::Ready(Some(Ok(frame))) => {
                if let Some(data) = frame.data_ref() {
                    if let Err(e) = this.scan(data) {
                        return Poll::Ready(Some(Err(Box::new(e))));
                    }
                }
                Poll::Ready(Some(Ok(frame)))
            }
            Poll::Ready(Some(Err(e))) => Poll::Ready(Some(Err(e.into()))),
            other => other.map(|f| f.map(|r| r.map_err(Into::into))),
        }
    }

    fn is_end_stream(&self) -> bool {
        self.inner.is_end_stream()
    }

    fn size_hint(&self) -> SizeHint {
        self.inner.size_hint()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_that_end_pass_and_one_that_does_not_fails() {
        let mut ok = PartHeaders::new(Body::empty(), "b");
        let body = b"--b\r\nContent-Disposition: form-data; name=\"spec\"\r\n\r\n{}\r\n--b\r\nContent-Disposition: form-data; name=\"image\"; filename=\"x\"\r\n\r\n";
        for chunk in body.chunks(7) {
            ok.scan(chunk).unwrap();
        }
        // a large part's data (no delimiter in it) is not a header
        ok.scan(&vec![b'a'; 1 << 20]).unwrap();
        ok.scan(b"\r\n--b--\r\n").unwrap();
        let mut endless = PartHeaders::new(Body::empty(), "b");
        endless.scan(b"--b\r\nX-Pad: ").unwrap();
        let pad = vec![b'a'; 16 << 10];
        let failed = (0..8).map(|_| endless.scan(&pad)).find(|r| r.is_err());
        assert!(failed.is_some(), "a header of 128 KiB fails");
    }
}
