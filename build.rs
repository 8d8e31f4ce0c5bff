//! Build script: migrations trigger a rebuild; the examples/*.json specs are
//! gathered into `$OUT_DIR/examples.json` for the viewer page's submit form
//! (`[{"name", "spec", "inputs"}]`, `inputs` the `input:NAME` files a spec needs);
//! and the servers some tests need are looked for ([`test_tools`]).

use std::fmt::Write;
use std::path::{Path, PathBuf};

fn main() {
    test_tools();
    println!("cargo:rerun-if-changed=migrations/sqlite");
    println!("cargo:rerun-if-changed=migrations/postgres");
    println!("cargo:rerun-if-changed=examples");
    let mut names: Vec<_> = std::fs::read_dir("examples")
        .expect("examples/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    names.sort();
    let mut out = String::from("[");
    for (k, path) in names.iter().enumerate() {
        let text = std::fs::read_to_string(path).expect("example spec");
        let name = path.file_stem().unwrap().to_string_lossy();
        let inputs: Vec<String> = text
            .split("\"input:")
            .skip(1)
            .filter_map(|rest| rest.split('"').next())
            .map(|n| format!("\"{}\"", n.escape_default()))
            .collect();
        let sep = if k == 0 { "" } else { "," };
        write!(
            out,
            "{sep}\n{{\"name\": {}, \"spec\": {}, \"inputs\": [{}]}}",
            quote(&name),
            quote(&text),
            inputs.join(", ")
        )
        .unwrap();
    }
    out.push_str("\n]\n");
    std::fs::write(std::path::Path::new(&std::env::var("OUT_DIR").unwrap()).join("examples.json"), out).unwrap();
}

/// `s` as a JSON string.
fn quote(s: &str) -> String {
    let mut q = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => q.push_str("\\\""),
            '\\' => q.push_str("\\\\"),
            '\n' => q.push_str("\\n"),
            '\r' => q.push_str("\\r"),
            '\t' => q.push_str("\\t"),
            c if (c as u32) < 0x20 => write!(q, "\\u{:04x}", c as u32).unwrap(),
            c => q.push(c),
        }
    }
    q.push('"');
    q
}

/// The tools the cluster tests (PostgreSQL, SeaweedFS) and the viewer page's
/// test (Chromium) need, looked for here so that a test that cannot run where
/// it is shows as ignored, with its reason, in the test runner's summary
/// (`cfg(shapeflow_cluster)`, `cfg(shapeflow_browser)`); with
/// `SHAPEFLOW_REQUIRE_POSTGRES`, `SHAPEFLOW_REQUIRE_S3` or
/// `SHAPEFLOW_REQUIRE_BROWSER` set (`.ci/run`) a missing tool fails the build.
/// The places looked at are watched: installing a tool later is seen.
fn test_tools() {
    println!("cargo:rustc-check-cfg=cfg(shapeflow_cluster)");
    println!("cargo:rustc-check-cfg=cfg(shapeflow_browser)");
    println!("cargo:rustc-check-cfg=cfg(shapeflow_mount)");
    // root with CAP_SYS_ADMIN: the tests may mount a small tmpfs (a disk that fills up)
    if can_mount() {
        println!("cargo:rustc-cfg=shapeflow_mount");
    }
    for var in [
        "SHAPEFLOW_REQUIRE_POSTGRES",
        "SHAPEFLOW_REQUIRE_S3",
        "SHAPEFLOW_REQUIRE_BROWSER",
        "SHAPEFLOW_WEED",
        "CHROMIUM",
    ] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    let watch = |path: &Path| {
        // the nearest existing folder (a missing path would rerun this script every build)
        let mut p = path.to_path_buf();
        while !p.exists() && p.pop() {}
        if p.exists() {
            println!("cargo:rerun-if-changed={}", p.display());
        }
    };
    let postgres = std::fs::read_dir("/usr/lib/postgresql")
        .map(|d| d.filter_map(|e| e.ok()).any(|e| e.path().join("bin/pg_ctl").exists()))
        .unwrap_or(false);
    watch(Path::new("/usr/lib/postgresql"));
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/seaweedfs/bin/weed");
    let weed = std::env::var_os("SHAPEFLOW_WEED").map(PathBuf::from).unwrap_or(venv);
    let s3 = weed.exists() || on_path("weed");
    watch(&weed);
    let chromium = PathBuf::from(std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into()));
    watch(&chromium);
    let browser = chromium.exists();
    let require = |var: &str, found: bool, what: &str| {
        if std::env::var_os(var).is_some() && !found {
            panic!("{var} is set but {what} is not installed");
        }
    };
    require("SHAPEFLOW_REQUIRE_POSTGRES", postgres, "PostgreSQL (/usr/lib/postgresql/*/bin/pg_ctl)");
    require("SHAPEFLOW_REQUIRE_S3", s3, "SeaweedFS (target/seaweedfs/bin/weed, $SHAPEFLOW_WEED or weed on PATH)");
    require("SHAPEFLOW_REQUIRE_BROWSER", browser, "Chromium (/usr/bin/chromium or $CHROMIUM)");
    if postgres && s3 {
        println!("cargo:rustc-cfg=shapeflow_cluster");
    }
    if browser {
        println!("cargo:rustc-cfg=shapeflow_browser");
    }
}

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(program).is_file()))
}

/// Whether this process may mount filesystems (effective CAP_SYS_ADMIN, bit 21).
fn can_mount() -> bool {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let cap = status.lines().find_map(|l| l.strip_prefix("CapEff:")).map(str::trim);
    cap.and_then(|c| u64::from_str_radix(c, 16).ok()).is_some_and(|c| c & (1 << 21) != 0)
}
