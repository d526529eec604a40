//! The repository is self-contained (issue 42, item 1): no tracked file refers to a path outside
//! the repository (the sibling `shared` folder some machines have beside the clone) or to a path
//! of one machine (an absolute path under the `work` or `home` folders, a GPU host's `.gpu`
//! staging folder): [`FORBIDDEN`] spells them. The meshes the docs, tests and benches use are
//! built in (`bunny`, `armadillo`: oit-core's `assets/`), so nothing needs such a path.
//!
//! `bench/results/` is left out: its files are historical records of how each run was made,
//! kept as they were written.
//!
//! Needs git (`git ls-files`); without it, or outside a git checkout (a packaged crate), the test
//! says so and passes.
//!
//! Mutations that make it fail: put the bunny's old path (`models/bunny.obj` in the sibling
//! `shared` folder) back into README.md's `--scene`, or oit-wgpu's gpu_setup test's absolute
//! path of it back into its `BUNNY`, or drop the `bench/results/` exclusion below (its READMEs
//! name the old staging script), or empty `FORBIDDEN` (`patterns_catch_what_they_name` fails
//! then). This file spells the patterns in pieces (`concat!`) so it does not match itself.

use std::path::Path;
use std::process::Command;

/// What no tracked file may contain. Spelled in pieces so this file does not match itself.
const FORBIDDEN: &[&str] = &[
    concat!("..", "/shared/"),
    concat!("/wo", "rk/"),
    concat!("/ho", "me/"),
    concat!("/ro", "ot/"),
    concat!(".gp", "u/"),
];

/// Historical records, left as they were written.
const EXCLUDED: &[&str] = &["bench/results/"];

/// The (line number, pattern) of every forbidden reference in `text`.
fn offences(text: &str) -> Vec<(usize, &'static str)> {
    text.lines()
        .enumerate()
        .flat_map(|(i, line)| FORBIDDEN.iter().filter(move |p| line.contains(**p)).map(move |p| (i + 1, *p)))
        .collect()
}

#[test]
fn patterns_catch_what_they_name() {
    let bad = format!("oit render --scene {}models/bunny.obj\nfine\ncd {}main", FORBIDDEN[0], FORBIDDEN[1]);
    assert_eq!(offences(&bad), vec![(1, FORBIDDEN[0]), (3, FORBIDDEN[1])]);
    assert!(offences("--scene bunny, grid:4x4:armadillo, models/dragon.obj, ../oit-core/assets").is_empty());
}

#[test]
fn no_tracked_file_refers_outside_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let listed = match Command::new("git").args(["ls-files", "-z"]).current_dir(&root).output() {
        Ok(out) if out.status.success() => out.stdout,
        Ok(out) => {
            eprintln!(
                "note: `git ls-files` failed ({}): not a git checkout? The self-contained check is skipped",
                String::from_utf8_lossy(&out.stderr).trim()
            );
            return;
        }
        Err(e) => {
            eprintln!("note: git cannot be run ({e}); the self-contained check is skipped");
            return;
        }
    };
    let files: Vec<String> = listed
        .split(|&b| b == 0)
        .filter(|f| !f.is_empty())
        .map(|f| String::from_utf8_lossy(f).into_owned())
        .filter(|f| !EXCLUDED.iter().any(|e| f.starts_with(e)))
        .collect();
    assert!(files.len() > 50, "git listed only {} files: is {} the repository?", files.len(), root.display());
    let mut found = Vec::new();
    for file in &files {
        // deleted in the working tree, or binary (the compressed meshes): nothing to read as text
        let Ok(text) = std::fs::read_to_string(root.join(file)) else { continue };
        for (line, pattern) in offences(&text) {
            found.push(format!("{file}:{line}: refers to {pattern}"));
        }
    }
    assert!(
        found.is_empty(),
        "{} reference(s) to a path outside the repository or of one machine (use the built-in `bunny` / \
         `armadillo`, a path inside the repository, or a variable):\n{}",
        found.len(),
        found.join("\n")
    );
}
