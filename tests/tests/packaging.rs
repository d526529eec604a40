//! Every library crate is ready to publish (issue 42, item 6), checked cheaply: nothing here
//! builds a packaged crate (that takes minutes; `bench/local/package.sh` does it).
//!
//! - [`metadata_is_complete`]: each published crate's manifest has a description, the
//!   workspace's licence and repository, `readme = "README.md"`, 1 to 5 keywords and categories
//!   from crates.io's list (the slugs this workspace uses, [`CATEGORIES`]), and each workspace
//!   dependency it has carries a version (a path alone is refused by `cargo package`).
//! - [`packages_hold_what_they_embed`]: `cargo package --list` succeeds for each and lists its
//!   README and the files its code embeds (oit-core's meshes and their terms, oit-bench's font,
//!   its licence and the calibrations); no manifest warning.
//! - [`shipped_calibrations_are_the_committed_results`]: oit-bench's `data/` copies of the
//!   committed calibrations (a packaged crate holds only its own folder, so it cannot
//!   `include_str!` them from `bench/results/`) are the same bytes as those results, which stay
//!   the one source: rerunning a calibration means copying it into `oit-bench/data/` too.
//!
//! Mutations that make it fail: drop `keywords` from a crate's manifest, or the
//! `version` of a sibling in the workspace's `[workspace.dependencies]`; add `"assets/"` to
//! oit-core's `exclude`; change one value of `oit-bench/data/cpu-calibration.json`.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The crates published to crates.io, and what each package must hold beyond its manifest and
/// README.
const PUBLISHED: &[(&str, &[&str])] = &[
    (
        "oit-core",
        &[
            "assets/bunny.obj.gz",
            "assets/armadillo.obj.gz",
            "assets/README.md",
            "assets/scenes/particles.glb.gz",
            "assets/scenes/foliage.glb.gz",
            "assets/scenes/glass.glb.gz",
            "assets/scenes/cad.glb.gz",
        ],
    ),
    ("oit-shaders", &["wgsl/core/common.wgsl"]),
    ("oit-gpu", &[]),
    ("oit-cpu", &[]),
    ("oit-wgpu", &[]),
    ("oit-vulkan", &["build.rs"]),
    (
        "oit-bench",
        &[
            "data/cpu-calibration.json",
            "data/h200-calibration.json",
            "assets/DejaVuSans.ttf",
            "assets/DejaVuSans-LICENSE.txt",
        ],
    ),
    ("oit-cli", &[]),
];

/// The crates.io category slugs this workspace uses (from <https://crates.io/category_slugs>); a
/// slug outside crates.io's list is refused at publish time, so a typo fails here first.
const CATEGORIES: &[&str] =
    &["graphics", "rendering", "development-tools::profiling", "visualization", "command-line-utilities"];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ has a parent").to_path_buf()
}

fn cargo() -> Command {
    let mut cmd = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    cmd.current_dir(root());
    cmd
}

/// `cargo metadata` of the workspace's own packages (no dependencies: nothing is resolved).
fn metadata() -> serde_json::Value {
    let out = cargo()
        .args(["metadata", "--no-deps", "--format-version", "1", "--offline"])
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "cargo metadata: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("cargo metadata writes JSON")
}

#[test]
fn metadata_is_complete() {
    let meta = metadata();
    let packages = meta["packages"].as_array().expect("packages");
    let workspace: Vec<&str> = packages.iter().filter_map(|p| p["name"].as_str()).collect();
    for (name, _) in PUBLISHED {
        let p =
            packages.iter().find(|p| p["name"] == *name).unwrap_or_else(|| panic!("{name} in the workspace"));
        let field = |key: &str| p[key].as_str().unwrap_or_default().to_string();
        assert!(!field("description").is_empty(), "{name}: no description");
        assert_eq!(field("license"), "MIT OR Apache-2.0", "{name}: license");
        assert!(field("repository").starts_with("https://"), "{name}: no repository");
        let readme = field("readme");
        assert!(readme.ends_with("README.md"), "{name}: readme is {readme:?}");
        assert!(
            Path::new(&readme).is_file() || root().join(name).join(&readme).is_file(),
            "{name}: {readme} missing"
        );
        let keywords = p["keywords"].as_array().expect("keywords");
        assert!(
            (1..=5).contains(&keywords.len()),
            "{name}: {} keywords (crates.io takes 1 to 5)",
            keywords.len()
        );
        for k in keywords {
            let k = k.as_str().unwrap_or_default();
            assert!(
                k.len() <= 20 && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_'),
                "{name}: keyword {k:?} is not one crates.io takes"
            );
        }
        let categories = p["categories"].as_array().expect("categories");
        assert!((1..=5).contains(&categories.len()), "{name}: {} categories", categories.len());
        for c in categories {
            assert!(
                CATEGORIES.contains(&c.as_str().unwrap_or_default()),
                "{name}: category {c} not in CATEGORIES"
            );
        }
        // a sibling dependency (normal or build; dev-dependencies are dropped from a package
        // without a version) needs a version beside its path
        for d in p["dependencies"].as_array().expect("dependencies") {
            let dep = d["name"].as_str().unwrap_or_default();
            if workspace.contains(&dep) && d["kind"] != "dev" {
                assert!(d["req"] != "*", "{name} depends on {dep} by path alone: give it a version");
            }
        }
    }
}

#[test]
fn packages_hold_what_they_embed() {
    for (name, embedded) in PUBLISHED {
        let out = cargo()
            .args(["package", "--list", "--allow-dirty", "--offline", "-p", name])
            .output()
            .expect("cargo runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "cargo package --list -p {name}: {stderr}");
        assert!(!stderr.contains("warning"), "cargo package --list -p {name} warns: {stderr}");
        let files: Vec<&str> = std::str::from_utf8(&out.stdout).expect("UTF-8 list").lines().collect();
        for file in ["Cargo.toml", "README.md", "src/lib.rs"].iter().chain(embedded.iter()) {
            assert!(files.contains(file), "{name}'s package lacks {file}: {files:?}");
        }
    }
}

#[test]
fn shipped_calibrations_are_the_committed_results() {
    let root = root();
    for (shipped, committed) in [
        ("oit-bench/data/cpu-calibration.json", "bench/results/cpu/calibration.json"),
        ("oit-bench/data/h200-calibration.json", "bench/results/h200/calibration.json"),
    ] {
        // the same calibration, value for value; only its `command_line` may differ (a run on a
        // lent machine names that machine's output folder, which a shipped crate must not)
        let read = |path: &str| -> serde_json::Value {
            let text = std::fs::read_to_string(root.join(path)).unwrap_or_else(|e| panic!("{path}: {e}"));
            let mut v: serde_json::Value =
                serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
            v.as_object_mut().expect("a calibration object").remove("command_line");
            v
        };
        assert!(
            read(shipped) == read(committed),
            "{shipped} differs from {committed}, the committed result: copy it over (cp {committed} {shipped})"
        );
    }
}
