//! The layer rule of ARCHITECTURE.md: a module of `src/` imports only from layers
//! below its own. The layers are read from ARCHITECTURE.md's table; every
//! `crate::<module>` path in a module's files (outside its test modules) must name a
//! module of a lower layer, so there is no upward import and no cycle between
//! modules.

use std::collections::HashMap;
use std::path::Path;

/// Module → layer, from the rows `| n | \`a\`, \`b\` | … |` of ARCHITECTURE.md.
fn layers(root: &Path) -> HashMap<String, usize> {
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let mut out = HashMap::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 4 {
            continue;
        }
        let Ok(layer) = cells[1].parse::<usize>() else { continue };
        for name in cells[2].split(',') {
            out.insert(name.trim().trim_matches('`').to_string(), layer);
        }
    }
    out
}

/// The `crate::<module>` names used in `text` before its first `#[cfg(test)]`.
fn crate_paths(text: &str) -> Vec<(usize, String)> {
    let code = text.split("#[cfg(test)]").next().unwrap_or_default();
    let mut out = Vec::new();
    for (n, line) in code.lines().enumerate() {
        let line = line.split("//").next().unwrap_or_default();
        let mut rest = line;
        while let Some(i) = rest.find("crate::") {
            let name: String = rest[i + 7..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            out.push((n + 1, name));
            rest = &rest[i + 7..];
        }
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn every_module_imports_only_from_lower_layers() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let layers = layers(root);
    assert!(layers.len() >= 10, "the layer table of ARCHITECTURE.md: {layers:?}");
    let mut violations = Vec::new();
    for entry in std::fs::read_dir(root.join("src")).unwrap() {
        let dir = entry.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        let module = dir.file_name().unwrap().to_string_lossy().to_string();
        let own = *layers.get(&module).unwrap_or_else(|| panic!("src/{module} is not in ARCHITECTURE.md's layers"));
        let mut files = Vec::new();
        rust_files(&dir, &mut files);
        for file in files {
            let text = std::fs::read_to_string(&file).unwrap();
            for (line, used) in crate_paths(&text) {
                if used == module {
                    continue;
                }
                match layers.get(&used) {
                    Some(&l) if l < own => {}
                    Some(&l) => violations.push(format!(
                        "{}:{line}: {module} (layer {own}) uses {used} (layer {l})",
                        file.strip_prefix(root).unwrap().display()
                    )),
                    None => {} // crate-root items (lib.rs)
                }
            }
        }
    }
    assert!(violations.is_empty(), "imports against the layer order:\n{}", violations.join("\n"));
}

/// The sibling modules of a folder that `text` names (`super::x`, `crate::m::x`).
fn sibling_uses(text: &str, module_path: &str, siblings: &[String]) -> Vec<String> {
    let code = text.split("#[cfg(test)]").next().unwrap_or_default();
    let mut out = Vec::new();
    for line in code.lines() {
        let line = line.split("//").next().unwrap_or_default();
        for prefix in ["super::".to_string(), format!("crate::{module_path}::")] {
            let mut rest = line;
            while let Some(i) = rest.find(&prefix) {
                let name: String =
                    rest[i + prefix.len()..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
                if siblings.contains(&name) && !out.contains(&name) {
                    out.push(name);
                }
                rest = &rest[i + prefix.len()..];
            }
        }
    }
    out
}

/// No import cycle between the files of one folder either: within every folder of
/// `src/`, the graph of which sibling module names which (`super::x`,
/// `crate::folder::x`; `mod.rs`, which declares and re-exports them, left out) has
/// no cycle.
#[test]
fn no_import_cycle_between_the_files_of_a_folder() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut dirs = vec![root.clone()];
    let mut cycles = Vec::new();
    while let Some(dir) = dirs.pop() {
        let mut siblings = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path.clone());
                siblings.push(path.file_name().unwrap().to_string_lossy().to_string());
            } else if path.extension().is_some_and(|e| e == "rs") && !path.ends_with("mod.rs") {
                siblings.push(path.file_stem().unwrap().to_string_lossy().to_string());
            }
        }
        if dir == root {
            continue; // the crate root's folders are the layers, checked above
        }
        let module_path = dir.strip_prefix(&root).unwrap().to_string_lossy().replace('/', "::");
        let source = |name: &str| {
            let file = dir.join(format!("{name}.rs"));
            std::fs::read_to_string(if file.exists() { file } else { dir.join(name).join("mod.rs") })
                .unwrap_or_default()
        };
        let graph: HashMap<String, Vec<String>> = siblings
            .iter()
            .map(|s| (s.clone(), sibling_uses(&source(s), &module_path, &siblings)))
            .map(|(s, mut uses)| {
                uses.retain(|u| *u != s);
                (s, uses)
            })
            .collect();
        // depth-first search for a back edge
        fn visit(
            n: &str,
            graph: &HashMap<String, Vec<String>>,
            state: &mut HashMap<String, u8>,
            stack: &mut Vec<String>,
            found: &mut Vec<String>,
        ) {
            state.insert(n.to_string(), 1);
            stack.push(n.to_string());
            for m in &graph[n] {
                match state.get(m.as_str()) {
                    Some(1) => {
                        let at = stack.iter().position(|s| s == m).unwrap();
                        found.push([&stack[at..], std::slice::from_ref(m)].concat().join(" → "));
                    }
                    Some(_) => {}
                    None => visit(m, graph, state, stack, found),
                }
            }
            stack.pop();
            state.insert(n.to_string(), 2);
        }
        let mut state = HashMap::new();
        let mut names: Vec<&String> = graph.keys().collect();
        names.sort();
        for n in names {
            if !state.contains_key(n.as_str()) {
                let mut found = Vec::new();
                visit(n, &graph, &mut state, &mut Vec::new(), &mut found);
                cycles.extend(found.into_iter().map(|c| format!("src/{}: {c}", module_path.replace("::", "/"))));
            }
        }
    }
    assert!(cycles.is_empty(), "import cycles between files:\n{}", cycles.join("\n"));
}
