//! The viewer page (docs/viewer.md): `GET /` (the job list and the submit form) and
//! `GET /jobs/{id}` (one job) answer the same HTML; `GET /ui/{path}` its scripts,
//! style and the vendored three.js (web/vendor/three, MIT licence). Every file is
//! embedded in the binary, so the page works offline with no build step. The page
//! holds no data: it reads the API with the token the user types in, so these
//! routes need no token.

use super::ApiError;
use axum::extract::Path;
use axum::http::header;
use axum::response::{IntoResponse, Response};

/// The page's files: (path under /ui/, media type, contents).
const FILES: &[(&str, &str, &[u8])] = &[
    ("app.js", JS, include_bytes!("../../../web/app.js")),
    ("dom.js", JS, include_bytes!("../../../web/dom.js")),
    ("api.js", JS, include_bytes!("../../../web/api.js")),
    ("jobs.js", JS, include_bytes!("../../../web/jobs.js")),
    ("job.js", JS, include_bytes!("../../../web/job.js")),
    ("form.js", JS, include_bytes!("../../../web/form.js")),
    ("plot.js", JS, include_bytes!("../../../web/plot.js")),
    ("scene.js", JS, include_bytes!("../../../web/scene.js")),
    ("style.css", "text/css; charset=utf-8", include_bytes!("../../../web/style.css")),
    ("examples.json", "application/json", include_bytes!(concat!(env!("OUT_DIR"), "/examples.json"))),
    ("vendor/three/LICENSE", "text/plain; charset=utf-8", include_bytes!("../../../web/vendor/three/LICENSE")),
    (
        "vendor/three/build/three.module.min.js",
        JS,
        include_bytes!("../../../web/vendor/three/build/three.module.min.js"),
    ),
    ("vendor/three/build/three.core.min.js", JS, include_bytes!("../../../web/vendor/three/build/three.core.min.js")),
    (
        "vendor/three/addons/loaders/GLTFLoader.js",
        JS,
        include_bytes!("../../../web/vendor/three/addons/loaders/GLTFLoader.js"),
    ),
    (
        "vendor/three/addons/utils/BufferGeometryUtils.js",
        JS,
        include_bytes!("../../../web/vendor/three/addons/utils/BufferGeometryUtils.js"),
    ),
    (
        "vendor/three/addons/utils/SkeletonUtils.js",
        JS,
        include_bytes!("../../../web/vendor/three/addons/utils/SkeletonUtils.js"),
    ),
    (
        "vendor/three/addons/controls/OrbitControls.js",
        JS,
        include_bytes!("../../../web/vendor/three/addons/controls/OrbitControls.js"),
    ),
];

const JS: &str = "text/javascript; charset=utf-8";

const INDEX: &str = include_str!("../../../web/index.html");

/// Whether `path` is one of the page's routes, which need no token.
pub(super) fn is_page(path: &str) -> bool {
    path == "/" || path.starts_with("/ui/") || (path.starts_with("/jobs/") && !path[6..].contains('/'))
}

/// `GET /` and `GET /jobs/{id}`: the page (its script reads the path).
pub(super) async fn index() -> Response {
    ([(header::CONTENT_TYPE, "text/html; charset=utf-8"), (header::CACHE_CONTROL, "no-cache")], INDEX).into_response()
}

/// `GET /jobs/{id}`: the page, opened on one job; 404 for what cannot be a job's id.
pub(super) async fn job_page(Path(id): Path<String>) -> Result<Response, ApiError> {
    uuid::Uuid::parse_str(&id).map_err(|_| ApiError::NotFound(format!("no job {id}: a job's id is a UUID")))?;
    Ok(index().await)
}

/// `GET /ui/{path}`: one of the page's files.
pub(super) async fn asset(Path(path): Path<String>) -> Result<Response, ApiError> {
    let (_, media, bytes) = FILES
        .iter()
        .find(|(p, _, _)| *p == path)
        .ok_or_else(|| ApiError::NotFound(format!("no file /ui/{path} of the viewer page")))?;
    Ok(([(header::CONTENT_TYPE, *media), (header::CACHE_CONTROL, "no-cache")], *bytes).into_response())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn page_routes_are_told_apart_from_the_api() {
        assert!(is_page("/") && is_page("/ui/app.js") && is_page("/jobs/abc"));
        assert!(!is_page("/v1/jobs") && !is_page("/jobs/abc/results") && !is_page("/healthz"));
    }

    /// Every module the page imports is served.
    #[test]
    fn every_import_of_the_page_is_served() {
        for (name, _, bytes) in FILES.iter().filter(|(p, _, _)| p.ends_with(".js") && !p.starts_with("vendor")) {
            let text = std::str::from_utf8(bytes).unwrap();
            for line in text.lines().filter(|l| l.starts_with("import ")) {
                let target = line.rsplit(['"', '\'']).nth(1).unwrap();
                if let Some(local) = target.strip_prefix("./") {
                    assert!(FILES.iter().any(|(p, _, _)| *p == local), "{name} imports {target}");
                } else {
                    assert!(target == "three" || target.starts_with("three/addons/"), "{name} imports {target}");
                }
            }
        }
    }
}
