//! The listener of the notification channel: one connection per node,
//! forwarding every notification (a job's id) to the node's broadcast channel.

use sqlx::postgres::{PgListener, PgPool};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::broadcast;

/// Forward the notifications of `channel` to `events` from a task that listens
/// on its own connection; after a lost connection (which may have dropped
/// notifications) it sends `"*"`, on which every stream re-reads.
pub(super) fn forward(pool: PgPool, channel: &'static str, events: broadcast::Sender<Arc<str>>) {
    tokio::spawn(async move {
        loop {
            let mut listener = match PgListener::connect_with(&pool).await {
                Ok(l) => l,
                Err(e) => {
                    tracing::warn!("event listener: {e}; retrying");
                    tokio::time::sleep(Duration::from_millis(500)).await;
                    continue;
                }
            };
            if let Err(e) = listener.listen(channel).await {
                tracing::warn!("event listener: {e}; retrying");
                tokio::time::sleep(Duration::from_millis(500)).await;
                continue;
            }
            let _ = events.send(Arc::from("*"));
            loop {
                match listener.try_recv().await {
                    Ok(Some(n)) => {
                        let _ = events.send(Arc::from(n.payload()));
                    }
                    // reconnected: notifications may have been missed
                    Ok(None) => {
                        let _ = events.send(Arc::from("*"));
                    }
                    Err(e) => {
                        tracing::warn!("event listener: {e}; reconnecting");
                        let _ = events.send(Arc::from("*"));
                        tokio::time::sleep(Duration::from_millis(200)).await;
                        break;
                    }
                }
            }
        }
    });
}
