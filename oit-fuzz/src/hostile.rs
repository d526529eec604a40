//! The hostile classes of issue 41 that byte edits alone rarely reach, made on purpose:
//!
//! - **non-regular files**: FIFOs in the worker's scratch folder (`hostile/model.obj`,
//!   `hostile/calibration.json`, `hostile/script.txt`, `hostile/report/report.json`,
//!   `hostile/materials.mtl`, `hostile/texture.png`), which scene and argument inputs name as
//!   `@hostile/…` (the worker puts its folder in), directly or through the regular OBJ files
//!   beside them whose `mtllib` or `map_Kd` names one (or `/dev/zero`). `open()` on a FIFO
//!   waits for a writer, so a reader that opens before it checks hangs, and the supervisor
//!   reports the hang;
//! - **huge polygons**: lone random stars of 65,536 corners (the most a face may have: each
//!   must load, its triangles covering the star exactly once, [`check_star`]) and 65,537 (refused
//!   by name), replayed by every worker, and one generated OBJ input in 512 a star of 16,384 to
//!   65,537 corners;
//! - **empty-coverage rows and replot round trips**: `bench --replot` of the corpus's reports
//!   (`reports/empty` holds rows of a frame that covered no pixel, EPR `null`); every report the
//!   args target accepts is drawn again into the scratch folder and read back ([`round_trip`]).

use std::path::{Path, PathBuf};

use oit_core::Scene;

/// What inputs write for the worker's folder of FIFOs.
pub const PLACEHOLDER: &str = "@hostile";

/// The FIFOs made in the worker's scratch folder, relative to its `hostile/`.
const FIFOS: &[&str] =
    &["model.obj", "calibration.json", "script.txt", "report/report.json", "materials.mtl", "texture.png"];

/// Regular files made beside the FIFOs that name them: an OBJ whose `mtllib` is a FIFO, and one
/// whose material's `map_Kd` is (the hostile re-run of 2026-12-05 found both hanging, and
/// `mtllib /dev/zero` read until the OOM killer came).
const FILES: &[(&str, &str)] = &[
    ("materials.obj", "mtllib materials.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
    (
        "textured.obj",
        "mtllib textured.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n",
    ),
    ("textured.mtl", "newmtl m\nd 0.5\nmap_Kd texture.png\n"),
    ("zero.obj", "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
];

/// Makes `scratch/hostile/` and its FIFOs (with `mkfifo`: the workspace forbids the `unsafe`
/// that libc's would take), and answers the folder.
pub fn prepare(scratch: &Path) -> Result<PathBuf, String> {
    let dir = scratch.join("hostile");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("report")).map_err(|e| format!("{}: {e}", dir.display()))?;
    for (name, text) in FILES {
        std::fs::write(dir.join(name), text).map_err(|e| format!("{}: {e}", dir.join(name).display()))?;
    }
    for name in FIFOS {
        let path = dir.join(name);
        let made = std::process::Command::new("mkfifo").arg(&path).status();
        if !made.is_ok_and(|s| s.success()) {
            return Err(format!(
                "mkfifo {} failed: the non-regular file class needs coreutils' mkfifo",
                path.display()
            ));
        }
    }
    Ok(dir)
}

/// `input` with every `@hostile` replaced by `dir` (its bytes as they are elsewhere).
pub fn expand(input: &[u8], dir: &Path) -> Vec<u8> {
    let with = dir.as_os_str().as_encoded_bytes();
    let from = PLACEHOLDER.as_bytes();
    let mut out = Vec::with_capacity(input.len());
    let mut i = 0;
    while i < input.len() {
        if input[i..].starts_with(from) {
            out.extend_from_slice(with);
            i += from.len();
        } else {
            out.push(input[i]);
            i += 1;
        }
    }
    out
}

/// A lone star polygon of `n` corners at even angles with radii in [0.2, 1) from `seed`, as OBJ
/// text: its vertices and one face.
pub fn random_star(n: usize, seed: u64) -> String {
    use std::fmt::Write;
    let mut state = seed | 1;
    let mut text = String::with_capacity(n * 30);
    for i in 0..n {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let r = 0.2 + 0.8 * (state >> 11) as f64 / (1u64 << 53) as f64;
        let a = i as f64 / n as f64 * std::f64::consts::TAU;
        // six decimals: corners 2·10⁻⁵ apart at the least, a 65,536-corner star in 2 MB
        let _ = writeln!(text, "v {:.6} {:.6} 0", r * a.cos(), r * a.sin());
    }
    text.push('f');
    for i in 1..=n {
        let _ = write!(text, " {i}");
    }
    text.push('\n');
    text
}

/// The inputs of `target` every worker replays after the corpus (too large to commit).
pub fn seeds(target: crate::Target) -> Vec<Vec<u8>> {
    match target {
        crate::Target::Obj => vec![
            random_star(oit_core::MAX_FACE_CORNERS, 0x41_0003).into_bytes(),
            random_star(oit_core::MAX_FACE_CORNERS + 1, 0x41_0003).into_bytes(),
        ],
        _ => Vec::new(),
    }
}

/// The polygon of `text` when it is one lone face (`v x y 0` lines, then one `f` of plain
/// positive indices, each vertex once, in order) that winds strictly counter-clockwise around the
/// origin: a simple polygon by construction, whatever mutation made it. `None` for anything else.
fn lone_star(text: &str) -> Option<Vec<(f64, f64)>> {
    let mut points = Vec::new();
    let mut face = None;
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") if face.is_none() => {
                let v: Vec<f32> = words.map(|w| w.parse::<f32>().ok()).collect::<Option<_>>()?;
                if v.len() != 3 || v[2] != 0.0 || !v[0].is_finite() || !v[1].is_finite() {
                    return None;
                }
                points.push((f64::from(v[0]), f64::from(v[1])));
            }
            Some("f") if face.is_none() => {
                let ix: Vec<usize> = words.map(|w| w.parse::<usize>().ok()).collect::<Option<_>>()?;
                face = Some(ix);
            }
            None => {}
            _ => return None,
        }
    }
    let face = face?;
    if face.len() < 4 || face.len() != points.len() || face.iter().enumerate().any(|(i, &ix)| ix != i + 1) {
        return None;
    }
    // each corner strictly after the one before it, turning less than half a turn, and one turn
    // in all: the polygon meets every ray from the origin once
    let mut turn = 0.0;
    for i in 0..points.len() {
        let (a, b) = (points[i], points[(i + 1) % points.len()]);
        let cross = a.0 * b.1 - a.1 * b.0;
        if cross <= 0.0 {
            return None;
        }
        turn += cross.atan2(a.0 * b.0 + a.1 * b.1);
    }
    ((turn - std::f64::consts::TAU).abs() < 1e-6).then_some(points)
}

/// For a lone star (see `lone_star`), that the loaded triangles cover it exactly once: their
/// unsigned areas add up to the polygon's (an overlap, or a triangle outside it, adds to the
/// sum) and none is turned over. Nothing to check for other inputs.
pub fn check_star(text: &str, scene: &Scene) {
    let Some(points) = lone_star(text) else { return };
    let n = points.len();
    let shoelace: f64 = (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum::<f64>()
        * 0.5;
    let mesh = &scene.meshes[0];
    let mut sum = 0.0;
    for t in &mesh.indices {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
        let z = (b - a).cross(c - a).z;
        assert!(z >= 0.0, "a star of {n} corners: a triangle turned over");
        sum += z * 0.5;
    }
    assert!(
        (sum - shoelace).abs() <= 1e-9 * shoelace,
        "a star of {n} corners: its triangles cover {sum}, the polygon {shoelace} (they overlap)"
    );
}

/// `bench --replot`'s round trip for a report it accepted in `from`: drawn again into
/// `scratch/replot`, the report read back must be the one read (empty rows' `null` EPR
/// included), and report.md shows no NaN.
pub fn round_trip(from: &Path, scratch: &Path) {
    let Ok(mut report) = oit_bench::read_report(from) else { return };
    let first = serde_json::to_value(&report).expect("a report serializes");
    let dir = scratch.join("replot");
    let _ = std::fs::remove_dir_all(&dir);
    report.files.clear();
    if let Err(e) = oit_bench::write_report(&mut report, &dir) {
        panic!("a report --replot accepted was not drawn again: {e}");
    }
    let again = oit_bench::read_report(&dir)
        .unwrap_or_else(|e| panic!("a report oit wrote is refused when read back: {e}"));
    let mut second = serde_json::to_value(&again).expect("a report serializes");
    second["files"] = first["files"].clone();
    assert!(first == second, "a report changed on its round trip through --replot");
    let md = std::fs::read_to_string(dir.join("report.md")).expect("report.md written");
    assert!(!md.contains("NaN"), "report.md shows NaN");
}
