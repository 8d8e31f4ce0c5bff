//! Helpers shared by the test binaries.

pub mod server;

use std::path::Path;
use std::process::Command;

/// Run the Khronos glTF-Validator (npm `gltf-validator`, installed by `npm ci`) over
/// `files`; panics with its report unless every file has no errors and no warnings.
#[allow(dead_code)] // not every test binary validates glTF
pub fn validate_gltf<P: AsRef<Path>>(files: &[P]) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert!(
        root.join("node_modules/gltf-validator").exists(),
        "the glTF validator is missing: run `npm ci` in {} first",
        root.display()
    );
    let out = Command::new("node")
        .arg(root.join("scripts/validate_gltf.mjs"))
        .args(files.iter().map(|f| f.as_ref()))
        .output()
        .expect("node");
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "validator: {report} {}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(report.lines().count(), files.len(), "{report}");
    assert!(report.lines().all(|l| l.contains("\"numErrors\":0,\"numWarnings\":0")), "{report}");
}

/// Validate JSON `files` against the JSON Schema `schema` with Ajv (npm `ajv`,
/// installed by `npm ci`): whether each file is valid, and Ajv's report line.
#[allow(dead_code)] // not every test binary validates JSON
pub fn validate_json_schema<P: AsRef<Path>>(schema: &Path, files: &[P]) -> Vec<(bool, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert!(root.join("node_modules/ajv").exists(), "Ajv is missing: run `npm ci` in {} first", root.display());
    let out = Command::new("node")
        .arg(root.join("scripts/validate_schema.mjs"))
        .arg(schema)
        .args(files.iter().map(|f| f.as_ref()))
        .output()
        .expect("node");
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "ajv: {report} {}", String::from_utf8_lossy(&out.stderr));
    let lines: Vec<(bool, String)> = report.lines().map(|l| (l.ends_with(": ok"), l.to_string())).collect();
    assert_eq!(lines.len(), files.len(), "{report}");
    lines
}
