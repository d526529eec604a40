//! Reads the shader tree (`wgsl/`) and writes `tree.rs` into `OUT_DIR`: `FILES`, every file of
//! the tree with its text, and `MODULES`, every module the tree declares. A module is declared
//! once, in the WGSL file it is about, by a comment line
//!
//! ```text
//! // module NAME (TAIL): SOURCE SOURCE ...
//! ```
//!
//! (TAIL one of `raster`, `kernels`, `alone`, `stage`; each SOURCE a path under `wgsl/`, in the
//! order they are joined), so a new technique's WGSL file is its own manifest entry and no list
//! of this crate changes. A line that does not parse, a source that is not in the tree and a name
//! declared twice stop the build with what is wrong and where.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"))
        .join("wgsl");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut files = Vec::new();
    walk(&root, &root, &mut files);
    files.sort();
    let mut out = String::from(
        "/// Every WGSL file of the tree (`wgsl/`, read by the build script): its path under `wgsl/`\n\
         /// and its text.\npub const FILES: &[(&str, &str)] = &[\n",
    );
    for (path, full) in &files {
        writeln!(out, "    ({path:?}, include_str!({:?})),", full.display().to_string())
            .expect("a String takes writes");
    }
    out.push_str(
        "];\n\n/// Every module both GPU backends build, each declared once by a `// module NAME (TAIL):\n\
         /// SOURCES` line of the WGSL file it is about (see the build script), in the order of the\n\
         /// tree's files.\npub const MODULES: &[Module] = &[\n",
    );
    let mut names: Vec<(String, String)> = Vec::new();
    for (path, full) in &files {
        let text = std::fs::read_to_string(full).unwrap_or_else(|e| panic!("wgsl/{path}: {e}"));
        for (n, line) in text.lines().enumerate() {
            let Some(rest) = line.strip_prefix("// module ") else { continue };
            let at = format!("wgsl/{path}:{}", n + 1);
            let (name, tail, sources) = parse(rest).unwrap_or_else(|why| {
                panic!("{at}: `{line}`: {why}; a module line reads `// module NAME (TAIL): SOURCE ...`")
            });
            for s in &sources {
                if !files.iter().any(|(p, _)| p == s) {
                    panic!("{at}: module {name} names {s}, which is not a file of wgsl/");
                }
            }
            if let Some((_, first)) = names.iter().find(|(n, _)| *n == name) {
                panic!("{at}: module {name} is declared already, at {first}");
            }
            names.push((name.clone(), at));
            let sources: Vec<String> = sources.iter().map(|s| format!("{s:?}")).collect();
            writeln!(
                out,
                "    Module {{ name: {name:?}, sources: &[{}], tail: Tail::{tail} }},",
                sources.join(", ")
            )
            .expect("a String takes writes");
        }
    }
    out.push_str("];\n");
    let dest = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("tree.rs");
    std::fs::write(&dest, out).unwrap_or_else(|e| panic!("{}: {e}", dest.display()));
}

/// Every `.wgsl` file below `dir`, as (path under `root` with `/`, full path).
fn walk(root: &Path, dir: &Path, files: &mut Vec<(String, PathBuf)>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.unwrap_or_else(|e| panic!("{}: {e}", dir.display())).path();
        if path.is_dir() {
            walk(root, &path, files);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            let rel = path.strip_prefix(root).expect("below the root").to_string_lossy().replace('\\', "/");
            files.push((rel, path));
        }
    }
}

/// `NAME (TAIL): SOURCE ...` as (name, the `Tail` variant, sources).
fn parse(rest: &str) -> Result<(String, &'static str, Vec<String>), String> {
    let (head, sources) = rest.split_once(':').ok_or("no `:` before the sources")?;
    let (name, tail) = head.trim().split_once(' ').ok_or("no `(TAIL)` after the name")?;
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!("`{name}` is not a module name (letters, digits, `_`)"));
    }
    let tail = match tail.trim() {
        "(raster)" => "Raster",
        "(kernels)" => "Kernels",
        "(alone)" => "Alone",
        "(stage)" => "Stage",
        other => return Err(format!("`{other}` is not a tail: (raster), (kernels), (alone) or (stage)")),
    };
    let sources: Vec<String> = sources.split_whitespace().map(str::to_string).collect();
    if sources.is_empty() {
        return Err("no sources".into());
    }
    Ok((name.to_string(), tail, sources))
}
