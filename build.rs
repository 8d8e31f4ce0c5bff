//! Build script: migrations trigger a rebuild; the examples/*.json specs are
//! gathered into `$OUT_DIR/examples.json` for the viewer page's submit form
//! (`[{"name", "spec", "inputs"}]`, `inputs` the `input:NAME` files a spec needs).

use std::fmt::Write;

fn main() {
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
