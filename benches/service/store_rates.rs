//! The store's own rates, with no HTTP in front of it: the latency of a claim
//! with 100,000 finished jobs in the table, and how many history batches the
//! database takes from 1, 4 and 16 writers at once.

use super::{percentile, SHORT};
use shapeflow::flow::Progress;
use shapeflow::service::store::{self, ClaimPolicy, JobStatus};
use std::time::{Duration, Instant};

/// Claim latency with 100,000 finished jobs in the table (bulk-inserted with SQL),
/// through the store with no workers running: 50 accepted jobs claimed one by one.
pub(super) async fn claims(database: &str, dir: &std::path::Path) {
    let blobs = shapeflow::service::blobs::Blobs::local(&dir.join("blobs")).unwrap();
    let st = store::open(database, blobs).await.unwrap();
    let bulk = if st.backend() == "postgres" {
        "INSERT INTO jobs (id, status, spec, created_at) \
         SELECT 'done-' || x, 'successful', '{}', '2026-01-01T00:00:00Z' FROM generate_series(1, 100000) x \
         ON CONFLICT DO NOTHING"
    } else {
        "INSERT INTO jobs (id, seq, status, spec, created_at) \
         WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c WHERE x < 100000) \
         SELECT 'done-' || x, 1000000 + x, 'successful', '{}', '2026-01-01T00:00:00Z' FROM c"
    };
    if database.starts_with("postgres") {
        let pool = sqlx::PgPool::connect(database).await.unwrap();
        sqlx::query(bulk).execute(&pool).await.unwrap();
    } else {
        let pool = sqlx::SqlitePool::connect(&format!("sqlite:{database}")).await.unwrap();
        sqlx::query(bulk).execute(&pool).await.unwrap();
    }
    let mut ids = Vec::new();
    for k in 0..50 {
        let id = format!("claim-{}-{k}", std::process::id());
        st.insert_job(&id, SHORT, &Default::default(), &Default::default()).await.unwrap();
        ids.push(id);
    }
    let policy = ClaimPolicy::default();
    let mut lat = Vec::new();
    for _ in 0..50 {
        let t = Instant::now();
        let c = st.claim_next("bench", &policy).await.unwrap().expect("an accepted job");
        lat.push(t.elapsed().as_secs_f64() * 1e3);
        st.finish(&c.job.id, Some(&c.lease), JobStatus::Successful, None, None, None).await.unwrap();
    }
    println!();
    println!("| claim with 100,000 finished jobs in the table | count | p50 | p99 |");
    println!("|---|---|---|---|");
    println!(
        "| claim_next | 50 | {:.2} ms | {:.2} ms |",
        percentile(&mut lat.clone(), 0.5),
        percentile(&mut lat, 0.99)
    );
    batch_rate(&st, &policy).await;
}

/// History batches as workers write them (`JobStore::record`: the fence, 64
/// history rows, the notification), from 1, 4 and 16 writers at once for 3 s, each
/// on a running job of its own: how many batches and rows per second the database
/// takes.
async fn batch_rate(st: &store::Store, policy: &ClaimPolicy) {
    println!();
    println!("| history batches of 64 rows, 3 s | batches/s | rows/s | p50 | p99 |");
    println!("|---|---|---|---|---|");
    for writers in [1, 4, 16] {
        let mut tasks = Vec::new();
        for k in 0..writers {
            st.insert_job(
                &format!("batch-{}-{writers}-{k}", std::process::id()),
                SHORT,
                &Default::default(),
                &Default::default(),
            )
            .await
            .unwrap();
            let c = st.claim_next("bench", policy).await.unwrap().expect("an accepted job");
            let st = st.clone();
            tasks.push(tokio::spawn(async move {
                let (mut lat, mut iteration, start) = (Vec::new(), 0, Instant::now());
                while start.elapsed() < Duration::from_secs(3) {
                    let rows: Vec<Progress> = (0..64)
                        .map(|_| {
                            iteration += 1;
                            Progress {
                                iteration,
                                time: 0.0,
                                tau: 1e-3,
                                energy: 1.0,
                                vertices: 256,
                                components: 1,
                                surgery: None,
                            }
                        })
                        .collect();
                    let t = Instant::now();
                    st.record(&c.job.id, &c.lease, &rows, &[]).await.unwrap();
                    lat.push(t.elapsed().as_secs_f64() * 1e3);
                }
                st.finish(&c.job.id, Some(&c.lease), JobStatus::Successful, None, None, None).await.unwrap();
                lat
            }));
        }
        let mut lat = Vec::new();
        for t in tasks {
            lat.extend(t.await.unwrap());
        }
        let rate = lat.len() as f64 / 3.0;
        println!(
            "| {writers} writer{} | {rate:.0} | {:.0} | {:.2} ms | {:.2} ms |",
            if writers > 1 { "s" } else { "" },
            64.0 * rate,
            percentile(&mut lat.clone(), 0.5),
            percentile(&mut lat, 0.99)
        );
    }
}
