//! `GET /readyz`: whether this node can take work now (beside `/healthz`, which
//! says only that it answers). 503 problem+json, naming what is wrong, while the
//! database takes no writes, the blob store cannot be written or the data
//! directory's disk has less free space than the node's floor; 200 again once
//! they recover. Each check has [`CHECK_TIME`] to answer.

use crate::service::{ApiError, AppState};
use axum::extract::State;
use axum::Json;
use serde_json::{json, Value};
use std::time::Duration;

/// How long each check may take before it counts as failed.
const CHECK_TIME: Duration = Duration::from_secs(2);

pub(super) async fn readyz(State(state): State<AppState>) -> Result<Json<Value>, ApiError> {
    let mut wrong = Vec::new();
    match tokio::time::timeout(CHECK_TIME, state.store.writable()).await {
        Ok(Ok(())) => {}
        Ok(Err(e)) => wrong.push(format!("the database takes no writes ({e})")),
        Err(_) => wrong.push(format!("the database took more than {} s to take a write", CHECK_TIME.as_secs())),
    }
    let key = ["readyz", state.node.as_str()];
    let probe = state.store.blobs().put(&key, Vec::new());
    match tokio::time::timeout(CHECK_TIME, probe).await {
        Ok(Ok(())) => {}
        Ok(Err(_)) => wrong.push("the blob store cannot be written".to_string()),
        Err(_) => wrong.push(format!("the blob store took more than {} s to take a write", CHECK_TIME.as_secs())),
    }
    if let Some(free) = free_bytes(&state.data_dir) {
        if free < state.min_free_disk {
            wrong.push(format!(
                "the data disk has {} free, less than the floor of {}",
                crate::service::isolation::format_size(free),
                crate::service::isolation::format_size(state.min_free_disk)
            ));
        }
    }
    match wrong.is_empty() {
        true => Ok(Json(json!({ "status": "ready" }))),
        false => Err(ApiError::Unavailable(wrong.join("; "))),
    }
}

/// The bytes free to unprivileged users on the disk of `dir` (Unix).
fn free_bytes(dir: &std::path::Path) -> Option<u64> {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let path = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
        let mut s = std::mem::MaybeUninit::<libc::statvfs>::uninit();
        // SAFETY: statvfs(3) fills `s` for a NUL-terminated path; read only on success.
        let done = unsafe { libc::statvfs(path.as_ptr(), s.as_mut_ptr()) };
        if done != 0 {
            return None;
        }
        // SAFETY: statvfs returned 0: `s` is initialized.
        let s = unsafe { s.assume_init() };
        // (fsblkcnt_t and c_ulong are narrower than u64 on some targets)
        #[allow(clippy::unnecessary_cast)]
        Some(s.f_bavail as u64 * s.f_frsize as u64)
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}
