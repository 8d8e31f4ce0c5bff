//! `shapeflow serve` and `shapeflow worker`: a node of the service until SIGINT or
//! SIGTERM, its logs and its admin token.

use super::args::LogFormat;
use anyhow::{Context, Result};
use std::path::Path;

/// Log lines on standard error: text (colored on a terminal) or one JSON object a line.
pub(crate) fn init_logs(format: LogFormat) {
    use std::io::IsTerminal;
    let filter = tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into());
    let logs = tracing_subscriber::fmt().with_writer(std::io::stderr).with_env_filter(filter);
    match format {
        LogFormat::Text => logs.with_ansi(std::io::stderr().is_terminal()).init(),
        LogFormat::Json => logs.json().flatten_event(true).with_current_span(true).init(),
    }
}

/// The admin token: given, or the first line of `file`.
pub(crate) fn token_from(token: Option<String>, file: Option<&Path>) -> Result<Option<String>> {
    let Some(file) = file else { return Ok(token) };
    let text = std::fs::read_to_string(file).with_context(|| format!("--token-file {}", file.display()))?;
    let line = text.lines().next().unwrap_or("").trim().to_string();
    anyhow::ensure!(!line.is_empty(), "--token-file {}: the file has no token on its first line", file.display());
    Ok(Some(line))
}

/// Run a node: the HTTP API on `bind` (none: workers only) and the workers, until
/// SIGINT/SIGTERM.
pub(crate) async fn serve(
    bind: Option<(&str, shapeflow::service::http::HttpLimits)>,
    config: shapeflow::service::ServiceConfig,
) -> Result<()> {
    let shown = redact(&config.database);
    let workers = config.workers;
    let service = shapeflow::service::Service::start_with(config)
        .await
        .with_context(|| format!("cannot open database {shown}"))?;
    match bind {
        Some((bind, limits)) => {
            let listener =
                tokio::net::TcpListener::bind(bind).await.with_context(|| format!("cannot listen on {bind}"))?;
            tracing::info!(address = %listener.local_addr()?, database = %shown, workers, "shapeflow serving");
            let closing = service.state.closing.clone();
            let shutdown = async move {
                shutdown_signal().await;
                // end open event streams, or graceful shutdown would wait for them
                closing.store(true, std::sync::atomic::Ordering::Relaxed);
            };
            let drain = std::time::Duration::from_secs(10);
            shapeflow::service::http::serve(listener, service.router(), limits, shutdown, drain).await?;
        }
        None => {
            tracing::info!(database = %shown, workers, "shapeflow worker running");
            shutdown_signal().await;
        }
    }
    tracing::info!("shutting down: running jobs checkpoint and resume later");
    service.stop().await;
    Ok(())
}

/// A database URL without its password, for messages.
pub(crate) fn redact(database: &str) -> String {
    match (database.find("://"), database.rfind('@')) {
        (Some(scheme), Some(at)) if at > scheme => {
            let userinfo = &database[scheme + 3..at];
            let user = userinfo.split(':').next().unwrap_or("");
            format!("{}{user}:***{}", &database[..scheme + 3], &database[at..])
        }
        _ => database.to_string(),
    }
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        if let Ok(mut s) = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            s.recv().await;
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {},
        _ = term => {},
    }
}
