//! No import circles inside any crate of the workspace (issue 37, item 5): within a crate, the
//! top-level modules form a graph by their `crate::module` references, and that graph has no
//! cycle, so each crate's files stand in floors (oit-vulkan: device below record below the
//! rasterizers below the context below the techniques; oit-wgpu: the public embedding module
//! above the internal hardware path, never under it).
//!
//! The graph is read from the source: references in comments and in `#[cfg(test)]` modules are
//! left out (a test may reach anywhere), and a reference to the crate root's own items (`crate::Foo`
//! defined in lib.rs) is not an edge.
//!
//! Mutations that make it fail: `use crate::ctx::ACCT_BINDING;` in oit-vulkan's device.rs (ctx
//! uses device), or `use crate::embed::CaptureShader;` in oit-wgpu's hardware.rs (embed uses
//! hardware); `crate_graphs_are_read` fails when the reader finds no edge at all.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The crates checked, relative to the workspace root.
const CRATES: &[&str] = &[
    "oit-core",
    "oit-shaders",
    "oit-gpu",
    "oit-cpu",
    "oit-wgpu",
    "oit-vulkan",
    "oit-cli",
    "oit-bench",
    "oit-fuzz",
    "tests",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ is in the workspace").to_path_buf()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The crate's top-level module a file of `src/` belongs to (`None` for lib.rs / main.rs).
fn top_module(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let first = rel.components().next()?.as_os_str().to_string_lossy().to_string();
    let name = first.trim_end_matches(".rs").to_string();
    (name != "lib" && name != "main").then_some(name)
}

/// Top-level module → the top-level modules it names through `crate::`.
fn graph(krate: &str) -> BTreeMap<String, BTreeSet<String>> {
    let src = root().join(krate).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let tops: BTreeSet<String> = files.iter().filter_map(|f| top_module(&src, f)).collect();
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in &files {
        let Some(top) = top_module(&src, f) else { continue };
        let text = std::fs::read_to_string(f).expect("a source file");
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        let deps = g.entry(top.clone()).or_default();
        for line in code.lines() {
            let line = line.split("//").next().unwrap_or("");
            let mut rest = line;
            while let Some(at) = rest.find("crate::") {
                rest = &rest[at + "crate::".len()..];
                // `crate::{a, b::c}` names several
                let names: Vec<&str> = if let Some(group) = rest.strip_prefix('{') {
                    let end = group.find('}').unwrap_or(group.len());
                    group[..end].split(',').map(|n| n.trim().split("::").next().unwrap_or("")).collect()
                } else {
                    vec![rest.split(|c: char| !(c.is_alphanumeric() || c == '_')).next().unwrap_or("")]
                };
                for n in names {
                    if n != top && tops.contains(n) {
                        deps.insert(n.to_string());
                    }
                }
            }
        }
    }
    g
}

/// A cycle of `g`, if it has one (depth-first search, the path on the stack).
fn cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        v: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(v.to_string(), 1);
        path.push(v.to_string());
        for w in g.get(v).into_iter().flatten() {
            match state.get(w.as_str()).copied().unwrap_or(0) {
                0 => {
                    if let Some(c) = visit(w, g, state, path) {
                        return Some(c);
                    }
                }
                1 => {
                    let from = path.iter().position(|p| p == w).unwrap_or(0);
                    let mut c = path[from..].to_vec();
                    c.push(w.clone());
                    return Some(c);
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(v.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for v in g.keys() {
        if state.get(v.as_str()).copied().unwrap_or(0) == 0
            && let Some(c) = visit(v, g, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

#[test]
fn no_crate_has_an_import_circle() {
    let mut circles = Vec::new();
    for krate in CRATES {
        if let Some(c) = cycle(&graph(krate)) {
            circles.push(format!("{krate}: {}", c.join(" → ")));
        }
    }
    assert!(circles.is_empty(), "import circles:\n{}", circles.join("\n"));
}

/// The reader sees edges where there are some (else the check above could pass on nothing), and
/// finds a circle where one is made.
#[test]
fn crate_graphs_are_read() {
    let vulkan = graph("oit-vulkan");
    assert!(vulkan.get("ctx").is_some_and(|d| d.contains("device")), "ctx uses device: {vulkan:?}");
    let mut made = vulkan.clone();
    made.entry("device".into()).or_default().insert("ctx".into());
    assert!(cycle(&made).is_some(), "a circle made by hand is found");
}
