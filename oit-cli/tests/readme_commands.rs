//! Every command the README and the command guides (`docs/commands/*.md`) show runs (issue 42,
//! item 2). Their ```sh blocks are parsed, each document's in its own scratch folder; each
//! `oit …` line runs through this build's binary, in a scratch folder, as written but for
//! its sizes: `--size` becomes 64x64 (added to render, compare, sweep and bench where absent),
//! `--views` at most 3, bench's `--frames` 2 and `--warmup` 0, so the whole README runs in
//! seconds. Each `cargo …` line must be one this file knows (the install, the test command CI
//! runs, the feature builds): those build what this test runs, so they are checked, not run. Any
//! other line fails the test: a README command this file cannot run is a command nobody checks.
//! The viewer's lines (`oit view`, `xvfb-run oit view`) are left to `tests/view.rs`, which opens
//! its window under Xvfb.
//!
//! A command on a GPU backend (`--backend wgpu|vulkan|all`) is skipped, with one line saying so,
//! when this binary was built without that backend, or when the backend finds no device, unless
//! `OIT_REQUIRE_GPU=1` (CI), where a missing device fails.
//!
//! Mutations that make it fail: misspell an option in a README command (`--technqiue`), name a
//! scene that does not exist, or add a `cargo run` line the list below does not know.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// The `cargo` lines the README may show, checked rather than run: they build or test what this
/// test runs.
const CARGO_LINES: &[&str] = &[
    "cargo install --path oit-cli",
    "cargo test --workspace --release",
    "cargo build --release -p oit-cli",
    "cargo install --path oit-cli --no-default-features --features cpu",
    "cargo install --path oit-cli --features vulkan",
    "OIT_WRITE_README=1 cargo test --release -p oit-tests --test readme_tables",
    "cargo bench -p oit-bench",
    "cargo bench -p oit-bench --bench gltf_load",
    "cargo build --profile profiling -p oit-cli",
];

/// The documents whose commands run: the README and each command's guide.
fn documents() -> Vec<PathBuf> {
    let mut out = vec![root().join("README.md")];
    let mut guides: Vec<PathBuf> = std::fs::read_dir(root().join("docs/commands"))
        .expect("docs/commands")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    guides.sort();
    out.extend(guides);
    out
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("oit-cli is in the workspace").to_path_buf()
}

/// The lines of every ```sh block of `text`: comments dropped, `\` continuations joined.
fn sh_lines(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    let mut pending = String::new();
    for line in text.lines() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            inside = trimmed == "```sh";
            continue;
        }
        if !inside {
            continue;
        }
        let code = match trimmed.find(" #") {
            Some(at) => trimmed[..at].trim_end(),
            None if trimmed.starts_with('#') => "",
            None => trimmed,
        };
        if let Some(head) = code.strip_suffix('\\') {
            pending.push_str(head.trim_end());
            pending.push(' ');
            continue;
        }
        pending.push_str(code);
        let whole = pending.split_whitespace().collect::<Vec<_>>().join(" ");
        pending.clear();
        if !whole.is_empty() {
            out.push(whole);
        }
    }
    out
}

/// `args` with its sizes made small, as the file's documentation says.
fn small(args: &[&str]) -> Vec<String> {
    let sub = args.first().copied().unwrap_or("");
    let mut out: Vec<String> = Vec::new();
    let mut it = args.iter();
    let mut sized = false;
    while let Some(a) = it.next() {
        match *a {
            "--size" => {
                it.next();
                out.extend(["--size".into(), "64x64".into()]);
                sized = true;
            }
            "--views" => {
                let n: u32 = it.next().and_then(|v| v.parse().ok()).unwrap_or(3);
                out.extend(["--views".into(), n.min(3).to_string()]);
            }
            "--frames" | "--warmup" if sub == "bench" => {
                it.next();
                out.extend([a.to_string(), if *a == "--frames" { "2" } else { "0" }.into()]);
            }
            other => out.push(other.to_string()),
        }
    }
    if !sized && matches!(sub, "render" | "compare" | "sweep" | "bench") {
        out.extend(["--size".into(), "64x64".into()]);
    }
    if sub == "bench" && !out.iter().any(|a| a == "--no-curves") {
        out.push("--no-curves".into());
    }
    out
}

/// The GPU backend a command asks for, if any.
fn gpu_backend(args: &[&str]) -> Option<String> {
    let at = args.iter().position(|a| *a == "--backend")?;
    let b = args.get(at + 1)?;
    (*b != "cpu").then(|| b.to_string())
}

/// What `oit info --json` says of each backend compiled in: its name and whether it found a device.
fn backends() -> Vec<(String, bool)> {
    let out =
        Command::new(env!("CARGO_BIN_EXE_oit")).args(["info", "--json"]).output().expect("oit info runs");
    assert!(out.status.success(), "oit info --json: {}", String::from_utf8_lossy(&out.stderr));
    let info: Value = serde_json::from_slice(&out.stdout).expect("oit info --json is JSON");
    info["backends"]
        .as_array()
        .expect("info lists backends")
        .iter()
        .map(|b| (b["name"].as_str().unwrap_or("?").to_string(), b["available"] == true))
        .collect()
}

fn gpu_required() -> bool {
    std::env::var("OIT_REQUIRE_GPU").is_ok_and(|v| v == "1")
}

/// One line on stderr past the harness's capture: a skip must be seen in a passing run.
fn note(line: &str) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// Runs every command of one document in `dir`; returns how many ran.
fn run_document(path: &Path, dir: &Path, compiled: &[(String, bool)]) -> usize {
    let name = path.strip_prefix(root()).unwrap_or(path).display().to_string();
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{name}: {e}"));
    std::fs::create_dir_all(dir).expect("scratch folder");
    let mut ran = 0;
    for line in sh_lines(&text) {
        if line.starts_with("cargo ") || line.contains(" cargo ") {
            assert!(
                CARGO_LINES.contains(&line.as_str()),
                "{name} shows a cargo command this test does not know: {line}"
            );
            continue;
        }
        if line.starts_with("oit view") || line.starts_with("xvfb-run oit view") {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(
            words[0], "oit",
            "{name} shows a command that is neither oit nor a known cargo line: {line}"
        );
        assert!(
            !line.contains(['"', '\'', '$', '|', '>', '<', '&', ';', '*']),
            "{name}: `{line}`: a command is plain words, run without a shell"
        );
        let args = small(&words[1..]);
        if let Some(backend) = gpu_backend(&words[1..]) {
            let wanted: Vec<&str> = if backend == "all" { vec![] } else { vec![backend.as_str()] };
            if let Some(missing) = wanted.iter().find(|w| !compiled.iter().any(|(n, _)| n == *w)) {
                note(&format!(
                    "skipped `{line}` ({name}): this build has no {missing} backend (build with --features {missing})"
                ));
                continue;
            }
            if let Some(absent) = wanted.iter().find(|w| compiled.iter().any(|(n, ok)| n == *w && !ok)) {
                assert!(
                    !gpu_required(),
                    "OIT_REQUIRE_GPU=1 but {absent} finds no device for `{line}` ({name})"
                );
                note(&format!(
                    "skipped `{line}` ({name}): no Vulkan device for {absent} (apt-get install mesa-vulkan-drivers; \
                     OIT_REQUIRE_GPU=1 makes this a failure)"
                ));
                continue;
            }
        }
        let out = Command::new(env!("CARGO_BIN_EXE_oit"))
            .args(&args)
            .current_dir(dir)
            .output()
            .unwrap_or_else(|e| panic!("{line}: {e}"));
        assert!(
            out.status.success(),
            "{name}: `{line}` (run as `oit {}`) failed:\n{}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr)
        );
        ran += 1;
    }
    ran
}

#[test]
fn every_readme_command_runs() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let lines = sh_lines(&readme);
    assert!(lines.iter().any(|l| l == "oit render"), "the README shows its first command: {lines:?}");
    assert!(lines.iter().any(|l| l == "cargo test --workspace --release"), "and CI's test command");
    let scratch = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("readme-commands");
    let _ = std::fs::remove_dir_all(&scratch);
    let compiled = backends();
    for (i, doc) in documents().iter().enumerate() {
        let ran = run_document(doc, &scratch.join(i.to_string()), &compiled);
        if i == 0 {
            assert!(ran >= 3, "the README's oit commands ran ({ran})");
        }
    }
}

#[test]
fn sizes_are_made_small_and_blocks_parsed() {
    assert_eq!(small(&["render"]), ["render", "--size", "64x64"]);
    assert_eq!(
        small(&["sweep", "--views", "200", "--size", "512x512"]),
        ["sweep", "--views", "3", "--size", "64x64"]
    );
    assert_eq!(
        small(&["bench", "--frames", "10", "--warmup", "1"]),
        ["bench", "--frames", "2", "--warmup", "0", "--size", "64x64", "--no-curves"]
    );
    assert_eq!(small(&["info"]), ["info"]);
    let text = "x\n```sh\noit render   # a comment\n# alone\noit bench --a \\\n    --b\n```\n```rust\nlet x = 1;\n```\n";
    assert_eq!(sh_lines(text), ["oit render", "oit bench --a --b"]);
}
