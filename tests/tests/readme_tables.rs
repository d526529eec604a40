//! The README's tables come from committed results, never typed by hand: each table between
//! `<!-- NAME: REPORT.json, scene SCENE; ... -->` and `<!-- /NAME -->` markers is what this file
//! writes from that report, and the test fails where the README differs. To regenerate after a new
//! run: `OIT_WRITE_README=1 cargo test --release -p oit-tests --test readme_tables`.
//!
//! Mutations that make it fail: edit any figure of the README's CPU table by hand, or commit a
//! new `bench/results/cpu/bench-bunny-512/report.json` without regenerating.

use std::path::PathBuf;

use serde_json::Value;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ is in the workspace").to_path_buf()
}

/// One number as the table prints it, or "n/a" where the report has none.
fn spread(v: &Value) -> String {
    let f = |k: &str| v[k].as_f64();
    match (f("median"), f("min"), f("max")) {
        (Some(m), Some(lo), Some(hi)) => format!("{m:.1} ({lo:.1}–{hi:.1})"),
        _ => "n/a".into(),
    }
}

/// The CPU trade table: technique, passes, lost, storage, wall ms with readback, EPR and PSNR.
fn cpu_trade_table(report: &Value, scene: &str) -> String {
    let mut out = vec![
        "| technique | passes | lost | storage | wall ms + readback, median (min–max) | EPR (%) | PSNR (dB) |".to_string(),
        "|---|---|---|---|---|---|---|".to_string(),
    ];
    let rows = report["rows"].as_array().expect("report.json has rows");
    for r in rows.iter().filter(|r| r["scene"] == scene && r["backend"] == "cpu") {
        let (epr, psnr) = match r["epr"].as_f64() {
            None => ("n/a".to_string(), "n/a".to_string()),
            Some(e) => {
                let pct = e * 100.0;
                let epr = if pct == 0.0 {
                    "0".to_string()
                } else if pct < 0.01 {
                    format!("{pct:.3}")
                } else if pct < 1.0 {
                    format!("{:.3}", pct).trim_end_matches('0').to_string()
                } else {
                    format!("{pct:.1}")
                };
                let psnr = match r["psnr"].as_f64() {
                    Some(p) if e > 0.0 && p.is_finite() => format!("{p:.1}"),
                    _ => "exact".to_string(),
                };
                (epr, psnr)
            }
        };
        let mib = r["storage_bytes"].as_f64().unwrap_or(0.0) / (1u64 << 20) as f64;
        let lost = r["lost"].as_u64().unwrap_or(0);
        out.push(format!(
            "| {} | {} | {} | {mib:.1} MiB | {} | {epr} | {psnr} |",
            r["technique"].as_str().unwrap_or("?"),
            r["passes"],
            lost,
            spread(&r["readback_wall_ms"]),
        ));
    }
    out.join("\n")
}

/// Every marked table of `readme` with the text its report gives.
fn regenerate(readme: &str) -> String {
    let mut out = String::new();
    let mut rest = readme;
    while let Some(at) = rest.find("<!-- cpu-trade-table: ") {
        let head_end = at + rest[at..].find("-->").expect("the marker closes") + 3;
        let head = &rest[at..head_end];
        let spec = head.trim_start_matches("<!-- cpu-trade-table: ");
        let (path, tail) = spec.split_once(", scene ").expect("marker names a report and a scene");
        let scene = tail.split(';').next().expect("a scene").trim();
        let report: Value = serde_json::from_str(
            &std::fs::read_to_string(root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}")),
        )
        .unwrap_or_else(|e| panic!("{path}: {e}"));
        let end =
            head_end + rest[head_end..].find("<!-- /cpu-trade-table -->").expect("the table's end marker");
        out.push_str(&rest[..head_end]);
        out.push('\n');
        out.push_str(&cpu_trade_table(&report, scene));
        out.push('\n');
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

#[test]
fn readme_tables_are_the_committed_results() {
    let path = root().join("README.md");
    let readme = std::fs::read_to_string(&path).expect("README.md");
    let fresh = regenerate(&readme);
    if std::env::var("OIT_WRITE_README").is_ok_and(|v| v == "1") {
        std::fs::write(&path, &fresh).expect("README.md written");
        return;
    }
    assert!(readme.contains("<!-- cpu-trade-table: "), "the README's CPU table has its markers");
    assert!(
        fresh == readme,
        "README.md's tables differ from the committed results they cite; run \
         OIT_WRITE_README=1 cargo test --release -p oit-tests --test readme_tables"
    );
}

/// The writer fails on a figure typed by hand: a table with one cell changed is not what the
/// report gives.
#[test]
fn a_hand_edited_figure_is_caught() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let fresh = regenerate(&readme);
    let edited = fresh.replacen("| dp | 9 |", "| dp | 8 |", 1);
    assert_ne!(edited, fresh, "the table has a dp row to edit");
    assert_ne!(regenerate(&edited), edited, "a hand edit is regenerated away");
}
