//! The library's top-level modules form a layered graph: no module reaches,
//! through `crate::` paths in its non-test code, a module that reaches it
//! back. Read from the sources, so a new cycle fails here, not in review.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

/// The top-level modules of `src/` (directories and files, not the binary).
fn modules(src: &Path) -> Vec<(String, Vec<PathBuf>)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(src).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        if matches!(name.as_str(), "lib" | "main" | "cli") {
            continue;
        }
        let mut files = Vec::new();
        collect(&path, &mut files);
        out.push((name, files));
    }
    out
}

fn collect(path: &Path, files: &mut Vec<PathBuf>) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).expect("module directory is readable") {
            collect(&entry.expect("a directory entry").path(), files);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        let stem = path.file_stem().unwrap().to_string_lossy();
        if stem != "tests" && !stem.ends_with("_tests") {
            files.push(path.to_path_buf());
        }
    }
}

/// The code of a file without its `#[cfg(test)]` module (always last).
fn non_test(text: &str) -> &str {
    text.find("#[cfg(test)]").map_or(text, |i| &text[..i])
}

fn graph(src: &Path) -> Graph {
    let mods = modules(src);
    let names: BTreeSet<String> = mods.iter().map(|(n, _)| n.clone()).collect();
    let mut g = Graph::new();
    for (name, files) in &mods {
        let uses = g.entry(name.clone()).or_default();
        for f in files {
            let text = std::fs::read_to_string(f).expect("source is readable");
            for part in non_test(&text).split("crate::").skip(1) {
                let target: String = part
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if &target != name && names.contains(&target) {
                    uses.insert(target);
                }
            }
        }
    }
    g
}

/// A cycle through `from`, if any: the path back to it.
fn cycle_from(g: &Graph, from: &str) -> Option<Vec<String>> {
    let mut stack = vec![(from.to_string(), vec![from.to_string()])];
    let mut seen = BTreeSet::new();
    while let Some((at, path)) = stack.pop() {
        for next in g.get(&at).into_iter().flatten() {
            if next == from {
                return Some([path.clone(), vec![next.clone()]].concat());
            }
            if seen.insert(next.clone()) {
                stack.push((next.clone(), [path.clone(), vec![next.clone()]].concat()));
            }
        }
    }
    None
}

#[test]
fn top_level_modules_are_acyclic() {
    let g = graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    assert!(g.len() > 10, "found only {:?}", g.keys());
    for m in g.keys() {
        if let Some(cycle) = cycle_from(&g, m) {
            panic!("module cycle: {}", cycle.join(" -> "));
        }
    }
}

#[test]
fn the_checker_finds_a_cycle() {
    let mut g = Graph::new();
    g.entry("store".into())
        .or_default()
        .insert("pipeline".into());
    g.entry("pipeline".into()).or_default().insert("io".into());
    assert_eq!(cycle_from(&g, "store"), None);
    g.entry("io".into()).or_default().insert("store".into());
    assert_eq!(
        cycle_from(&g, "store").unwrap(),
        ["store", "pipeline", "io", "store"]
    );
}

#[test]
fn the_memory_and_progress_layers_use_nothing_above_them() {
    let g = graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    for bottom in ["memory", "progress", "geom", "units", "stats", "rng"] {
        let uses = &g[bottom];
        assert!(uses.iter().all(|u| u == "units"), "{bottom} uses {uses:?}");
    }
}
