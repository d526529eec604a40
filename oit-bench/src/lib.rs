//! oit-bench: the speed/accuracy report of oit, and the criterion benches (`benches/`).
//!
//! Contract: [`run_bench`] renders, for every scene × backend (× raster path, one
//! [`oit_core::OnPath`] each) × technique, `warmup` untimed frames and then `frames` timed ones,
//! and returns a [`Report`] holding
//!
//! - one [`Row`] per run: passes, fragments, lost, storage, the median and spread (min, max,
//!   quartiles) of wall and GPU milliseconds, Gfrag/s, and EPR and PSNR against the reference of
//!   the same backend and path;
//! - the cost model's check ([`model`]): per scene and backend/path its statistics
//!   ([`StatsRow`]: triangles, pixels, fragments, the depth histogram), and, where a calibration
//!   is loaded ([`Config::model`]), each technique's predicted time and speedup over `dp` beside
//!   the measured ones ([`model::Prediction`]) and the error on the scenes the model was not
//!   calibrated on ([`model::ModelSummary`]);
//! - the cross-backend matrix ([`MatrixEntry`]): per technique, the largest 8-bit difference and
//!   the EPR between the images of every pair of backend/paths;
//! - the two curves ([`CurvePoint`]): time against depth complexity (`planes:N`) and against
//!   triangle count (`grid:RxC:MESH`).
//!
//! A run that fails is a [`Failure`] in the report, never the end of the bench. [`write_report`]
//! then writes `report.md`, `report.json` and the plots (SVG and PNG) into a folder.
//!
//! [`present`] is the presentation shared with the CLI: text in the embedded font, the heat
//! map's legend and contact sheets, drawn on top of what the backends return.
//!
//! "Time" in the model, the plots and Gfrag/s is the median GPU time where the backend measures it
//! (timestamps), else the median wall time; [`Row::time_source`] says which.
//!
//! Every input is checked before anything is rendered ([`Config::validate`]). The runs themselves
//! are [`experiment::Experiment`]'s reference-versus-techniques loop, the one `oit compare` and
//! `oit sweep` run too, and the backends come from the one registry, [`backends`].
//!
//! The loop on its own: backends by name from the registry, the reference and each technique at
//! each view, every technique measured against the reference (EPR a fraction in [0, 1]):
//!
//! ```
//! use oit_bench::backends::{select, BackendOptions};
//! use oit_bench::experiment::{Experiment, Step};
//! use oit_core::{load_scene, Settings, Technique, View};
//!
//! let backends = select("cpu", &BackendOptions::default())?;
//! let scene = load_scene("spheres:3")?;
//! let settings = Settings { width: 32, height: 32, ..Settings::default() };
//! let techniques = [Technique::Dp, Technique::WeightedAverage];
//! let experiment = Experiment {
//!     backends: &backends,
//!     settings: &settings,
//!     techniques: &techniques,
//!     warmup: 0,
//!     warmup_ms: 0,
//!     frames: 1,
//!     keep_images: false,
//! };
//! let views = [View { azimuth: 0.0, ..View::default() }, View { azimuth: 90.0, ..View::default() }];
//! let mut renders = 0;
//! let measurements = experiment.run("spheres:3", &scene, &views, &mut |step| {
//!     if let Step::Measured(_) = step {
//!         renders += 1;
//!     }
//! })?;
//! assert_eq!(renders, 2 * 3); // per view: the reference, dp, wavg
//! for m in measurements.iter().filter(|m| !m.baseline) {
//!     let measured = m.result.as_ref().expect("rendered");
//!     let epr = measured.accuracy.expect("measured against the reference").epr;
//!     match m.technique {
//!         Technique::Dp => assert_eq!(epr, 0.0), // exact
//!         _ => assert!(epr > 0.0 && epr <= 1.0), // wavg ignores order
//!     }
//! }
//! # Ok::<(), oit_core::OitError>(())
//! ```

/// The crate's README (what crates.io shows), whose example runs as a doc test with these.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod auto;
pub mod backends;
pub mod experiment;
pub mod model;
pub mod plot;
pub mod present;
mod report;

use std::collections::HashMap;

use experiment::{Experiment, Measurement, Step, label_of, measure};
use oit_core::metrics::accuracy;
use oit_core::plan::Plan;
use oit_core::{
    Backend, BlendTarget, Camera, Frame, HardwareCapture, Image, OitError, RasterPath, Scene, Settings,
    Technique, View, load_scene,
};
use serde::{Deserialize, Serialize};

pub use backends::available_backends;
pub use model::{ModelFile, pareto_front};
pub use report::{read_report, write_report};

/// What to measure.
pub struct Config {
    /// Scenes by name (anything [`oit_core::load_scene`] takes).
    pub scenes: Vec<String>,
    /// The scene of each glTF file to draw (`--gltf-scene N`, [`oit_core::load_scene_with`]);
    /// `None`: each file's default scene. With it, every scene must be a `.gltf` or `.glb` path.
    pub gltf_scene: Option<usize>,
    /// Backends, each pinned to a raster path or on its own default.
    pub backends: Vec<Box<dyn Backend>>,
    /// Image size, shading and the rest (the technique is set per run).
    pub settings: Settings,
    /// The camera's angles; each scene is framed from them.
    pub view: View,
    /// Techniques to time (the reference is rendered anyway, for accuracy).
    pub techniques: Vec<Technique>,
    /// Untimed frames before the timed ones.
    pub warmup: u32,
    /// Untimed frame loops after them, for at least this many milliseconds (`--warmup-ms`):
    /// lets a GPU that idled between rows clock up again ([`Experiment::warmup_ms`]).
    pub warmup_ms: u32,
    /// Timed frames (at least 1; the report asks for 10 or more).
    pub frames: u32,
    /// The two curves, or none.
    pub curves: Option<CurveConfig>,
    /// The command line, recorded in the report.
    pub command_line: String,
    /// The cost model to check, per backend/path (none: no predictions).
    pub model: Option<ModelFile>,
    /// Where the model came from, for the report.
    pub model_source: Option<String>,
    /// Narrower blend targets (`--blend-targets`) measured beside the default on the hardware
    /// path: rows of backend `NAME+f16` (`plain`, and `wavg`/`wsum` with the blend capture) and
    /// `NAME+unorm8` (`plain`), each against the reference like every row.
    pub blend_targets: Vec<BlendTarget>,
}

/// The scenes and runs of the two curves.
#[derive(Clone, Debug)]
pub struct CurveConfig {
    /// The mesh of `grid:RxC:MESH`.
    pub mesh: String,
    /// Techniques drawn.
    pub techniques: Vec<Technique>,
    /// The N of `planes:N`.
    pub depths: Vec<u32>,
    /// The R×C of `grid:RxC:MESH`.
    pub grids: Vec<(u32, u32)>,
    /// Image width of the curves' frames.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Timed frames per point (after one untimed).
    pub frames: u32,
}

impl CurveConfig {
    /// The defaults: dp, bdp, adp, fabs, mdts64; depths 1, 2, 4, …, 256; grids 1×1 to 4×4 of
    /// `mesh`; 128×128 frames; 3 timed frames per point.
    pub fn new(mesh: &str) -> CurveConfig {
        CurveConfig {
            mesh: mesh.to_string(),
            techniques: Technique::parse_list("dp,bdp,adp,fabs,mdts64").unwrap_or_default(),
            depths: (0..=8).map(|i| 1 << i).collect(),
            grids: vec![(1, 1), (1, 2), (2, 2), (2, 4), (4, 4)],
            width: 128,
            height: 128,
            frames: 3,
        }
    }
}

/// Median, extremes and quartiles of a set of times.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// The median.
    pub median: f64,
    /// The smallest.
    pub min: f64,
    /// The largest.
    pub max: f64,
    /// The first quartile (linear interpolation).
    pub q1: f64,
    /// The third quartile.
    pub q3: f64,
    /// How many values.
    pub samples: usize,
}

impl Spread {
    /// The spread of `values` (none when empty).
    pub fn of(values: &[f64]) -> Option<Spread> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let at = |q: f64| {
            let pos = q * (v.len() - 1) as f64;
            let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
            v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
        };
        Some(Spread {
            median: at(0.5),
            min: v[0],
            max: v[v.len() - 1],
            q1: at(0.25),
            q3: at(0.75),
            samples: v.len(),
        })
    }
}

/// One technique on one backend/path and scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// The scene.
    pub scene: String,
    /// The backend.
    pub backend: String,
    /// The raster path.
    pub raster: String,
    /// The technique, parameters included.
    pub technique: String,
    /// Geometry passes per frame.
    pub passes: u32,
    /// Fragments one geometry pass generates.
    pub fragments: u64,
    /// Fragments that reached the composite.
    pub captured: u64,
    /// Fragments that did not.
    pub lost: u64,
    /// Fragments `--overflow tail` merged behind the K nearest ([`oit_core::Stats::merged`]); 0
    /// in reports written before the tail existed.
    #[serde(default)]
    pub merged: u64,
    /// Fragments behind the opaque pass's depth ([`oit_core::Stats::occluded`]); 0 in a scene
    /// without opaque parts and in reports written before the opaque pass.
    #[serde(default)]
    pub occluded: u64,
    /// Fragments whose order against an equal-depth fragment the technique could not establish
    /// ([`oit_core::Stats::tied`]); 0 in reports written before it was counted.
    #[serde(default)]
    pub tied: u64,
    /// Fragments whose colour went through a lossy packing ([`oit_core::Stats::quantized`]: bdp's
    /// colour mode), so an EPR above 0 with nothing lost or tied is accounted for; 0 in reports
    /// written before it was carried here.
    #[serde(default)]
    pub quantized: u64,
    /// Bytes of per-pixel storage (the largest tile's, where the frame ran in tiles).
    pub storage_bytes: u64,
    /// Screen tiles the frame ran in ([`oit_core::Stats::tiles`]; `--memory`); 1 in reports
    /// written before frames were tiled.
    #[serde(default = "one")]
    pub tiles: u32,
    /// Wall milliseconds per frame, the image read back to the host (as `readback_wall_ms`; the
    /// name reports before the steady state was measured used).
    pub wall_ms: Spread,
    /// Wall milliseconds per steady-state frame: the same prepared scene after the warm-up, in a
    /// frame loop (`Prepared::frame_loop`: frames in flight where the backend keeps them, each
    /// frame's counters read back, not its image), the time between completions. `None` in
    /// reports written before it was measured; in reports before frames in flight, one frame at a
    /// time (as `latency_wall_ms` is now).
    #[serde(default)]
    pub steady_wall_ms: Option<Spread>,
    /// Wall milliseconds per frame rendered on its own and waited for before the next
    /// (`Prepared::frame_stats`): the steady state's latency. `None` in reports written before
    /// frames in flight.
    #[serde(default)]
    pub latency_wall_ms: Option<Spread>,
    /// Wall milliseconds per frame plus the readback of its image: `wall_ms` under its own name.
    #[serde(default)]
    pub readback_wall_ms: Option<Spread>,
    /// GPU milliseconds per frame (timestamps), where measured.
    pub gpu_ms: Option<Spread>,
    /// The time used for the model, the plots and Gfrag/s: `gpu_ms.median`, else
    /// `wall_ms.median`.
    pub time_ms: f64,
    /// `gpu` or `wall`: where `time_ms` comes from.
    pub time_source: String,
    /// Scene fragments resolved per second: `fragments / time_ms`, in 10⁹ per second.
    pub gfrag_per_s: f64,
    /// Error pixel rate against the same backend/path's reference, a fraction in [0, 1]
    /// (`report.md` and the plots show it in per cent); NaN, written `null`, when the frame
    /// covered no pixel (`n/a` in `report.md`, left out of the plots).
    #[serde(deserialize_with = "nan_if_null")]
    pub epr: f64,
    /// PSNR in dB against it; null when identical.
    pub psnr: Option<f64>,
    /// The largest channel difference from it, 8-bit steps.
    pub max_diff: u32,
    /// Device milliseconds per pass label of the last timed frame (geometry passes, kernels),
    /// where measured: where a technique's time goes.
    #[serde(default)]
    pub gpu_pass_ms: Vec<(String, f64)>,
    /// Geometry passes the technique's plan predicts from the scene's deepest pixel
    /// ([`model::geometry_passes`]); 0 in reports written before the model.
    #[serde(default)]
    pub model_passes: u32,
}

/// Reads a number that may be `null`: serde_json writes a NaN (an EPR over no covered pixel) as
/// `null`, so a report with such a row reads back as it was written.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A run that failed.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Failure {
    /// What was run (`bench`, `plain pass`, `depth curve`, `triangle curve`).
    pub stage: String,
    /// The scene.
    pub scene: String,
    /// The backend/path.
    pub backend: String,
    /// The technique.
    pub technique: String,
    /// Why.
    pub error: String,
    /// Refused under the run's settings (a combination the backend, path or technique does not
    /// do: [`experiment::Measurement::refused`]), not failed.
    #[serde(default)]
    pub refused: bool,
}

/// A scene's statistics on one backend/path: the cost model's inputs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StatsRow {
    /// The scene.
    pub scene: String,
    /// The backend/path label.
    pub backend: String,
    /// Triangles, pixels, fragments per pass and the depth histogram (from the reference's
    /// layers per pixel).
    pub stats: model::SceneStats,
}

/// One pair of backend/paths for one technique.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MatrixEntry {
    /// The scene.
    pub scene: String,
    /// The technique.
    pub technique: String,
    /// The first backend/path (its reference's coverage selects the pixels).
    pub a: String,
    /// The second.
    pub b: String,
    /// The largest channel difference between the two images, 8-bit steps.
    pub max_diff: u32,
    /// The share of covered pixels that differ by more than 1 step, a fraction in [0, 1]
    /// (`report.md` shows it in per cent); NaN, written `null`, when no pixel is covered.
    #[serde(deserialize_with = "nan_if_null")]
    pub epr: f64,
    /// The largest channel difference over pixels off projected triangle edges (more than a pixel
    /// from every edge), 8-bit steps: where a hardware rasterizer may cover other fragments than
    /// oit's fixed-point rules, only edge pixels may differ.
    #[serde(default)]
    pub max_diff_off_edges: u32,
    /// What the pair is held to: [`cross_check`]'s verdict (`None`: held and within; `Some`:
    /// why it was not held, or how it failed, as `failed` says).
    #[serde(default)]
    pub note: Option<String>,
    /// Whether the pair broke the conformance bound (also listed in the report's failures).
    #[serde(default)]
    pub failed: bool,
}

/// One side of a cross-backend comparison: a technique's frame on one backend/path.
#[derive(Clone, Debug)]
pub struct Side<'a> {
    /// `backend` or `backend/path`.
    pub label: &'a str,
    /// The raster path it ran on.
    pub raster: RasterPath,
    /// Its image.
    pub image: &'a Image,
    /// Fragments it lost (counted).
    pub lost: u64,
}

/// The conformance bounds of the cross-backend matrix (as the suite holds them in
/// `tests/tests/wgpu.rs`): two paths that share oit's fixed-point rules (oit-cpu, a compute
/// path) produce the same fragments, so no channel may differ by more than 1 (float order); a
/// hardware path may differ only on pixels within a pixel of a projected edge or of a line where
/// a transparent surface crosses an opaque one (`edges`, from [`oit_core::metrics::edge_mask`]
/// and [`oit_core::metrics::crossing_mask`]), and off them by at most 1. Not held: a technique that keeps
/// fragments in arrival order when it overflows (`fabs:K` with losses), whose survivors depend on
/// the device's scheduling, nor a pair of different `--blend-targets`. Returns (largest
/// difference off the edges, a note, failed).
pub fn cross_check(
    technique: Technique,
    a: &Side<'_>,
    b: &Side<'_>,
    edges: &[bool],
) -> (u32, Option<String>, bool) {
    let hardware = a.raster == RasterPath::Hardware || b.raster == RasterPath::Hardware;
    let none = vec![false; edges.len()];
    let mask = if hardware { edges } else { &none };
    let (worst, differ) = oit_core::metrics::differ_off_mask(a.image, b.image, mask);
    let worst = u32::from(worst);
    if matches!(technique, Technique::Fabs { k: Some(_) }) && (a.lost > 0 || b.lost > 0) {
        let note =
            "not held: fabs:K keeps the first K fragments to arrive, and arrival order is the device's";
        return (worst, Some(note.into()), false);
    }
    // rows of `--blend-targets` (`NAME+f16`, `NAME+unorm8`) round into a narrower target: held
    // only against rows of the same target
    let target = |label: &str| ["+f16", "+unorm8"].into_iter().find(|t| label.contains(t));
    if target(a.label) != target(b.label) && worst > 1 {
        let note = format!(
            "not held: {} and {} blend into different colour targets (the rounding is bounded in tests/tests/blend_target.rs)",
            a.label, b.label
        );
        return (worst, Some(note), false);
    }
    if worst <= 1 {
        return (worst, None, false);
    }
    let where_ = if hardware { "off triangle edges" } else { "anywhere (the same fixed-point fragments)" };
    let note = format!(
        "{} vs {}: {differ} pixels differ by up to {worst} 8-bit steps {where_}; the bound is 1",
        a.label, b.label
    );
    (worst, Some(note), true)
}

/// One point of a curve.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CurvePoint {
    /// `depth` (x: N of planes:N) or `triangles` (x: the grid scene's triangle count).
    pub curve: String,
    /// The scene.
    pub scene: String,
    /// The backend/path label.
    pub backend: String,
    /// The technique.
    pub technique: String,
    /// The x value.
    pub x: f64,
    /// Time, milliseconds (median, as [`Row::time_ms`]).
    pub time_ms: f64,
    /// Geometry passes.
    pub passes: u32,
    /// Fragments per pass.
    pub fragments: u64,
}

/// A backend/path that was measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BackendInfo {
    /// `name` or `name/path`.
    pub label: String,
    /// The device, in words.
    pub device: String,
}

/// 1: the screen tiles of a row read from a report written before frames were tiled.
fn one() -> u32 {
    1
}

/// A scene that was measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneInfo {
    /// Its name.
    pub name: String,
    /// Triangles.
    pub triangles: u64,
    /// Fragments of one pass (the first reference's), if one rendered.
    pub fragments: Option<u64>,
    /// The deepest pixel, if a reference rendered.
    pub max_depth: Option<u32>,
}

/// Everything measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    /// The command line.
    pub command_line: String,
    /// The host: CPU model and cores.
    pub host: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The camera's angles.
    pub view: View,
    /// Untimed frames per run.
    pub warmup: u32,
    /// Untimed frame loops per run after them, in milliseconds (`--warmup-ms`).
    #[serde(default)]
    pub warmup_ms: u32,
    /// Timed frames per run.
    pub frames: u32,
    /// The backend/paths.
    pub backends: Vec<BackendInfo>,
    /// The scenes.
    pub scenes: Vec<SceneInfo>,
    /// The table.
    pub rows: Vec<Row>,
    /// The cost model's inputs, per scene and backend/path.
    #[serde(default)]
    pub scene_stats: Vec<StatsRow>,
    /// Where the cost model came from (a calibration file), if one was loaded.
    #[serde(default)]
    pub model_source: Option<String>,
    /// The cost model's predictions beside the measurements.
    #[serde(default)]
    pub predictions: Vec<model::Prediction>,
    /// The check: per backend/path, the model's error on scenes it was not calibrated on.
    #[serde(default)]
    pub model_summary: Vec<model::ModelSummary>,
    /// The cross-backend matrix.
    pub matrix: Vec<MatrixEntry>,
    /// The curves' points.
    pub curves: Vec<CurvePoint>,
    /// The mesh of the triangle curve, if the curves ran.
    pub curve_mesh: Option<String>,
    /// The curves' image size, if they ran.
    pub curve_size: Option<(u32, u32)>,
    /// Runs that failed.
    pub failures: Vec<Failure>,
    /// Files written next to the report (filled by [`write_report`]).
    pub files: Vec<String>,
}

/// `name` or `name/path`: how a backend pinned to a path (or on its default for these settings)
/// is labelled.
pub fn label(backend: &dyn Backend, settings: &Settings) -> String {
    label_of(backend.name(), backend.raster_path(settings))
}

/// Most frames (timed or warm-up) one run takes.
pub const MAX_FRAMES: u32 = 100_000;

/// Largest N of the depth curve's `planes:N`.
pub const MAX_CURVE_DEPTH: u32 = 1 << 16;

/// Checks that `name` loads as a valid scene and that `view` frames it at `settings`' aspect.
pub fn check_scene(name: &str, view: View, settings: &Settings) -> Result<(), OitError> {
    check_scene_with(name, None, view, settings)
}

/// [`check_scene`] of scene `gltf_scene` of a glTF file ([`oit_core::load_scene_with`]).
pub fn check_scene_with(
    name: &str,
    gltf_scene: Option<usize>,
    view: View,
    settings: &Settings,
) -> Result<(), OitError> {
    let scene = oit_core::load_scene_with(name, gltf_scene)?;
    scene.validate()?;
    Camera::orbit_scene(&scene, view, settings.width as f32 / settings.height as f32)?;
    Ok(())
}

/// Checks a frame count (`what` names it in the message).
fn check_frames(n: u32, least: u32, what: &str) -> Result<(), OitError> {
    if (least..=MAX_FRAMES).contains(&n) {
        Ok(())
    } else {
        Err(OitError::InvalidSettings(format!("{what} {n} is out of range: use {least} to {MAX_FRAMES}")))
    }
}

impl CurveConfig {
    /// The scenes of the two curves: (curve, scene name, x where the name sets it).
    fn scenes(&self) -> Vec<(&'static str, String, Option<f64>)> {
        let mut scenes: Vec<(&str, String, Option<f64>)> =
            self.depths.iter().map(|&n| ("depth", format!("planes:{n}"), Some(f64::from(n)))).collect();
        scenes.extend(
            self.grids.iter().map(|&(r, c)| ("triangles", format!("grid:{r}x{c}:{}", self.mesh), None)),
        );
        scenes
    }

    /// Checks everything before any work: techniques, depths, grids, size and frames, and that
    /// every curve scene (the mesh included) loads and is framed by `view`. `settings` gives the
    /// shading and the rest; the curves' own size replaces its size.
    pub fn validate(&self, view: View, settings: &Settings) -> Result<(), OitError> {
        let bad = |m: String| Err(OitError::InvalidSettings(m));
        if self.techniques.is_empty() {
            return bad("the curves name no technique".into());
        }
        if self.depths.is_empty() || self.grids.is_empty() {
            return bad("the curves need at least one depth and one grid".into());
        }
        if let Some(n) = self.depths.iter().find(|&&n| !(1..=MAX_CURVE_DEPTH).contains(&n)) {
            return bad(format!(
                "depth curve: planes:{n} is out of range: use N from 1 to {MAX_CURVE_DEPTH}"
            ));
        }
        check_frames(self.frames, 1, "curve frames")?;
        let settings = Settings { width: self.width, height: self.height, ..settings.clone() };
        settings.validate().map_err(|e| OitError::InvalidSettings(format!("the curves' frames: {e}")))?;
        for (curve, name, _) in self.scenes() {
            check_scene(&name, view, &settings)
                .map_err(|e| OitError::InvalidSettings(format!("{curve} curve, scene {name}: {e}")))?;
        }
        Ok(())
    }
}

impl Config {
    /// Checks every input before any work: frame counts, backends, techniques, settings, that
    /// every scene loads and is framed, and the curves ([`CurveConfig::validate`]).
    pub fn validate(&self) -> Result<(), OitError> {
        check_frames(self.frames, 1, "timed frames")?;
        check_frames(self.warmup, 0, "warm-up frames")?;
        if self.backends.is_empty() {
            return Err(OitError::InvalidSettings("the bench needs at least one backend".into()));
        }
        if self.techniques.is_empty() {
            return Err(OitError::InvalidSettings("the bench names no technique".into()));
        }
        if self.scenes.is_empty() {
            return Err(OitError::InvalidSettings("the bench names no scene".into()));
        }
        self.settings.validate()?;
        for name in &self.scenes {
            check_scene_with(name, self.gltf_scene, self.view, &self.settings)?;
        }
        if let Some(curves) = &self.curves {
            curves.validate(self.view, &self.settings)?;
        }
        Ok(())
    }

    /// How many steps [`run_bench_with`] reports: per scene and backend the reference and each
    /// technique; per curve point and backend each curve technique.
    pub fn steps(&self) -> u64 {
        let b = self.backends.len() as u64;
        let main = self.scenes.len() as u64 * b * (self.techniques.len() as u64 + 1);
        let curves = self
            .curves
            .as_ref()
            .map_or(0, |c| (c.depths.len() + c.grids.len()) as u64 * b * c.techniques.len() as u64);
        main + curves
    }
}

/// Runs the bench with no progress report.
pub fn run_bench(config: &Config) -> Result<Report, OitError> {
    run_bench_with(config, &mut |_| {})
}

/// Issue 10.5: `wavg` and `wsum` on the hardware path by additive blending into float targets
/// (`--hardware-capture blend`, the form real renderers use) beside the default atomics capture,
/// so the report compares the two, time and error: rows of backend `NAME+blend` on the hardware
/// path, timed and measured against that backend/path's reference like every row. Then, for each
/// of `--blend-targets`, rows of backend `NAME+f16` or `NAME+unorm8`: the blender's techniques
/// (`plain`; `wavg`/`wsum` by blending where the target holds their sums) into that target.
/// None of the first when the bench runs neither weighted technique, no backend takes the
/// hardware path for them, or the settings ask for the blend capture already.
fn blend_rows(
    config: &Config,
    base: &Settings,
    scene_name: &str,
    scene: &Scene,
) -> Result<Vec<Measurement>, OitError> {
    let weighted_only = |t: &Technique| matches!(t, Technique::WeightedAverage | Technique::WeightedSum);
    let techniques: Vec<Technique> = config.techniques.iter().copied().filter(weighted_only).collect();
    let weighted = Settings { technique: Technique::WeightedAverage, ..base.clone() };
    let on_hardware = config.backends.iter().any(|b| b.raster_path(&weighted) == RasterPath::Hardware);
    let mut rows = Vec::new();
    if !techniques.is_empty() && on_hardware && base.hardware_capture != HardwareCapture::Blend {
        let settings = Settings { hardware_capture: HardwareCapture::Blend, ..base.clone() };
        rows.extend(hardware_rows(config, &settings, &techniques, scene_name, scene, "blend")?);
    }
    for &target in config.blend_targets.iter().filter(|&&t| t != base.blend_target) {
        let techniques: Vec<Technique> = config
            .techniques
            .iter()
            .copied()
            .filter(|t| *t == Technique::Plain || (weighted_only(t) && target != BlendTarget::Unorm8))
            .collect();
        if techniques.is_empty() {
            continue;
        }
        let settings =
            Settings { hardware_capture: HardwareCapture::Blend, blend_target: target, ..base.clone() };
        rows.extend(hardware_rows(config, &settings, &techniques, scene_name, scene, &target.to_string())?);
    }
    Ok(rows)
}

/// `techniques` under `settings` on each backend's hardware path, as rows of backend
/// `NAME+suffix` (the rows each backend's reference measures are dropped: the main rows have them).
fn hardware_rows(
    config: &Config,
    settings: &Settings,
    techniques: &[Technique],
    scene_name: &str,
    scene: &Scene,
    suffix: &str,
) -> Result<Vec<Measurement>, OitError> {
    let experiment = Experiment {
        backends: &config.backends,
        settings,
        techniques,
        warmup: config.warmup,
        warmup_ms: config.warmup_ms,
        frames: config.frames,
        keep_images: true,
    };
    let measured = experiment.run(scene_name, scene, &[config.view], &mut |_| {})?;
    Ok(measured
        .into_iter()
        .filter(|m| !m.baseline && m.raster == RasterPath::Hardware)
        .map(|mut m| {
            m.backend = format!("{}+{suffix}", m.backend);
            m
        })
        .collect())
}

/// The wall-time spread of timed frames.
fn wall_spread(wall: &[f64]) -> Spread {
    Spread::of(wall).unwrap_or_default()
}

/// The GPU-time spread, where every timed frame measured one.
fn gpu_spread(wall: &[f64], gpu: &[f64]) -> Option<Spread> {
    (gpu.len() == wall.len()).then(|| Spread::of(gpu)).flatten()
}

/// (time, source) as [`Row::time_ms`].
fn time_of(wall: &[f64], gpu: &[f64]) -> (f64, &'static str) {
    match gpu_spread(wall, gpu) {
        Some(g) => (g.median, "gpu"),
        None => (wall_spread(wall).median, "wall"),
    }
}

/// The host in words: CPU model (from /proc/cpuinfo where there is one) and cores.
pub fn host() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{model}, {cores} cores, {}", std::env::consts::OS)
}

/// Runs the bench, calling `on_step` with a description before each of [`Config::steps`] steps.
/// Every input is checked first ([`Config::validate`]): a bad one fails before any rendering.
pub fn run_bench_with(config: &Config, on_step: &mut dyn FnMut(&str)) -> Result<Report, OitError> {
    config.validate()?;
    let base = Settings { technique: Technique::Reference, ..config.settings.clone() };
    let mut report = Report {
        command_line: config.command_line.clone(),
        host: host(),
        width: base.width,
        height: base.height,
        view: config.view,
        warmup: config.warmup,
        warmup_ms: config.warmup_ms,
        frames: config.frames,
        backends: config
            .backends
            .iter()
            .map(|b| BackendInfo { label: label(b.as_ref(), &base), device: b.capabilities().device })
            .collect(),
        scenes: Vec::new(),
        rows: Vec::new(),
        scene_stats: Vec::new(),
        model_source: None,
        predictions: Vec::new(),
        model_summary: Vec::new(),
        matrix: Vec::new(),
        curves: Vec::new(),
        curve_mesh: config.curves.as_ref().map(|c| c.mesh.clone()),
        curve_size: config.curves.as_ref().map(|c| (c.width, c.height)),
        failures: Vec::new(),
        files: Vec::new(),
    };
    let fail = |report: &mut Report, stage: &str, scene: &str, backend: &str, technique: &str, e: &str| {
        report.failures.push(Failure {
            stage: stage.into(),
            scene: scene.into(),
            backend: backend.into(),
            technique: technique.into(),
            error: e.to_string(),
            refused: false,
        });
    };
    let experiment = Experiment {
        backends: &config.backends,
        settings: &base,
        techniques: &config.techniques,
        warmup: config.warmup,
        warmup_ms: config.warmup_ms,
        frames: config.frames,
        keep_images: true,
    };

    for scene_name in &config.scenes {
        let scene = oit_core::load_scene_with(scene_name, config.gltf_scene)?;
        let camera = Camera::orbit_scene(&scene, config.view, base.width as f32 / base.height as f32)?;
        let mut info = SceneInfo {
            name: scene_name.clone(),
            triangles: scene.triangle_count(),
            fragments: None,
            max_depth: None,
        };
        let mut measurements =
            experiment.run(scene_name, &scene, &[config.view], &mut |step| match step {
                Step::Rendering(what) => on_step(&format!("{scene_name}: {what}")),
                // nothing is measured on a backend whose reference failed
                Step::Measured(m) if m.baseline && m.result.is_err() => {
                    for _ in &config.techniques {
                        on_step(&format!("{scene_name}: skipped on {}", m.label()));
                    }
                }
                Step::Measured(_) => {}
            })?;
        measurements.extend(blend_rows(config, &base, scene_name, &scene)?);

        // per technique: (label, image, the coverage of that backend's reference)
        let mut images: HashMap<String, Vec<Rendered>> = HashMap::new();
        for (index, backend) in config.backends.iter().enumerate() {
            let backend = backend.as_ref();
            let mine: Vec<&Measurement> = measurements.iter().filter(|m| m.backend_index == index).collect();
            let Some(reference) = mine.iter().find(|m| m.baseline) else { continue };
            let ref_label = reference.label();
            let reference = match &reference.result {
                Ok(r) => r,
                Err(e) => {
                    fail(&mut report, "reference", scene_name, &ref_label, "reference", e);
                    on_step(&format!("{scene_name}: skipped on {ref_label}"));
                    continue;
                }
            };
            info.fragments.get_or_insert(reference.stats.fragments);
            if info.max_depth.is_none() {
                info.max_depth = reference.max_depth;
            }
            if let Some(image) = &reference.image {
                images.entry("reference".into()).or_default().push(Rendered {
                    label: ref_label.clone(),
                    raster: reference_raster(&mine),
                    technique: Technique::Reference,
                    image: image.clone(),
                    cover: reference.layers.clone(),
                    lost: reference.stats.lost,
                });
            }

            // the model's inputs: the scene's statistics from the reference's layers per pixel
            let stats = reference.layers.as_ref().map(|layers| {
                model::SceneStats::from_layers(scene.triangle_count(), reference.stats.fragments, layers)
            });
            if let Some(stats) = &stats {
                report.scene_stats.push(StatsRow {
                    scene: scene_name.clone(),
                    backend: ref_label.clone(),
                    stats: stats.clone(),
                });
            }
            let n = stats.as_ref().map_or(0, model::SceneStats::deepest);

            let mut measured: Vec<(Technique, Row)> = Vec::new();
            for m in mine.iter().filter(|m| !m.baseline) {
                let technique = m.technique.to_string();
                let r = match &m.result {
                    Ok(r) => r,
                    Err(e) => {
                        fail(&mut report, "bench", scene_name, &m.label(), &technique, e);
                        if let Some(f) = report.failures.last_mut() {
                            f.refused = m.refused;
                        }
                        continue;
                    }
                };
                let s = &r.stats;
                // no accuracy (nothing covered, or no reference): NaN, never a perfect score
                let acc = r.accuracy.unwrap_or_else(oit_core::metrics::Accuracy::unmeasured);
                let (time_ms, source) = time_of(&r.wall_ms, &r.gpu_ms);
                let row = Row {
                    scene: scene_name.clone(),
                    backend: m.backend.clone(),
                    raster: m.raster.to_string(),
                    technique: technique.clone(),
                    passes: s.geometry_passes,
                    fragments: s.fragments,
                    captured: s.captured,
                    lost: s.lost,
                    merged: s.merged,
                    occluded: s.occluded,
                    tied: s.tied,
                    quantized: s.quantized,
                    storage_bytes: s.storage_bytes,
                    tiles: s.tiles.max(1),
                    wall_ms: wall_spread(&r.wall_ms),
                    steady_wall_ms: Spread::of(&r.steady_wall_ms),
                    latency_wall_ms: Spread::of(&r.latency_wall_ms),
                    readback_wall_ms: Spread::of(&r.wall_ms),
                    gpu_ms: gpu_spread(&r.wall_ms, &r.gpu_ms),
                    time_ms,
                    time_source: source.into(),
                    gfrag_per_s: if time_ms > 0.0 {
                        s.fragments as f64 / (time_ms * 1e-3) / 1e9
                    } else {
                        0.0
                    },
                    epr: acc.epr,
                    psnr: acc.psnr.is_finite().then_some(acc.psnr),
                    max_diff: (acc.max_error * 255.0).round() as u32,
                    gpu_pass_ms: s.gpu_pass_ms.clone(),
                    model_passes: Plan::new(
                        backend.name(),
                        &scene,
                        &Settings { technique: m.technique, ..base.clone() },
                    )
                    .map_or(0, |plan| model::geometry_passes(&plan.on_path(m.raster), n)),
                };
                if let Some(image) = &r.image {
                    images.entry(technique).or_default().push(Rendered {
                        label: m.label(),
                        raster: m.raster,
                        technique: m.technique,
                        image: image.clone(),
                        cover: reference.layers.clone(),
                        lost: s.lost,
                    });
                }
                measured.push((m.technique, row));
            }

            report.rows.extend(measured.into_iter().map(|(_, r)| r));
        }

        // the matrix: every pair of backend/paths, per technique, held to the conformance bounds
        // and the lines where a transparent surface crosses an opaque one, where the paths'
        // depths may fall either side of the opaque depth
        let mut edges = oit_core::metrics::edge_mask(&scene, &camera, base.width, base.height, 1.0);
        let crossings = oit_core::metrics::crossing_mask(&scene, &camera, base.width, base.height, 1.0);
        edges.iter_mut().zip(crossings).for_each(|(e, c)| *e |= c);
        let mut names: Vec<String> = vec!["reference".into()];
        names.extend(config.techniques.iter().map(ToString::to_string));
        for technique in names {
            let Some(list) = images.get(&technique) else { continue };
            for i in 0..list.len() {
                for j in i + 1..list.len() {
                    let (a, b) = (&list[i], &list[j]);
                    let frame_a = Frame {
                        image: a.image.clone(),
                        layers: a.cover.clone(),
                        lost_pixels: None,
                        stats: Default::default(),
                    };
                    match accuracy(&frame_a, &b.image) {
                        Ok(acc) => {
                            let (off_edges, note, failed) =
                                cross_check(a.technique, &a.side(), &b.side(), &edges);
                            if failed {
                                let pair = format!("{} vs {}", a.label, b.label);
                                let why = note.clone().unwrap_or_default();
                                fail(&mut report, "matrix", scene_name, &pair, &technique, &why);
                            }
                            report.matrix.push(MatrixEntry {
                                scene: scene_name.clone(),
                                technique: technique.clone(),
                                a: a.label.clone(),
                                b: b.label.clone(),
                                max_diff: (acc.max_error * 255.0).round() as u32,
                                epr: acc.epr,
                                max_diff_off_edges: off_edges,
                                note,
                                failed,
                            })
                        }
                        Err(e) => fail(
                            &mut report,
                            "matrix",
                            scene_name,
                            &format!("{} vs {}", a.label, b.label),
                            &technique,
                            &e.to_string(),
                        ),
                    }
                }
            }
        }
        report.scenes.push(info);
    }

    if let Some(curves) = &config.curves {
        run_curves(config, curves, &mut report, on_step, fail)?;
    }
    if let Some(model) = &config.model {
        report.model_source.clone_from(&config.model_source);
        report.predictions = model::predict(model, &samples(&report));
        report.model_summary = model::summarize(&report.predictions);
    }
    Ok(report)
}

/// The report's runs as the cost model sees them: one [`model::Sample`] per row whose scene and
/// backend/path have statistics.
pub fn samples(report: &Report) -> Vec<model::Sample> {
    report
        .rows
        .iter()
        .filter_map(|r| {
            let raster = r.raster.parse().ok()?;
            let label = label_of(&r.backend, raster);
            // a `NAME+blend` row (`blend_rows`) draws the scene of NAME's statistics
            let measured = label_of(r.backend.split('+').next().unwrap_or(&r.backend), raster);
            let stats = report.scene_stats.iter().find(|s| s.scene == r.scene && s.backend == measured)?;
            Some(model::Sample {
                scene: r.scene.clone(),
                backend: label,
                technique: r.technique.clone(),
                passes: r.model_passes,
                measured_passes: r.passes,
                stats: stats.stats.clone(),
                time_ms: r.time_ms,
            })
        })
        .collect()
}

/// A technique's image on one backend/path, with the coverage of that backend's reference.
struct Rendered {
    label: String,
    raster: RasterPath,
    technique: Technique,
    image: Image,
    cover: Option<Vec<u32>>,
    lost: u64,
}

impl Rendered {
    fn side(&self) -> Side<'_> {
        Side { label: &self.label, raster: self.raster, image: &self.image, lost: self.lost }
    }
}

/// The raster path of a backend's measurements (the reference's).
fn reference_raster(mine: &[&Measurement]) -> RasterPath {
    mine.iter().find(|m| m.baseline).map_or(RasterPath::Cpu, |m| m.raster)
}

type FailFn = fn(&mut Report, &str, &str, &str, &str, &str);

fn run_curves(
    config: &Config,
    curves: &CurveConfig,
    report: &mut Report,
    on_step: &mut dyn FnMut(&str),
    fail: FailFn,
) -> Result<(), OitError> {
    let settings = Settings { width: curves.width, height: curves.height, ..config.settings.clone() };
    settings.validate()?;
    let aspect = curves.width as f32 / curves.height as f32;
    for (curve, name, x) in curves.scenes() {
        let steps = config.backends.len() * curves.techniques.len();
        let loaded = load_scene(&name)
            .and_then(|s| s.validate().map(|()| s))
            .and_then(|s| Camera::orbit_scene(&s, config.view, aspect).map(|c| (s, c)));
        let (scene, camera) = match loaded {
            Ok(sc) => sc,
            Err(e) => {
                fail(report, &format!("{curve} curve"), &name, "-", "-", &e.to_string());
                for _ in 0..steps {
                    on_step(&format!("{name}: skipped"));
                }
                continue;
            }
        };
        let x = x.unwrap_or(scene.triangle_count() as f64);
        for backend in &config.backends {
            // one prepared scene per backend and curve point, every technique's frames on it
            let mut prepared = backend.prepare(&scene);
            for &technique in &curves.techniques {
                let s = Settings { technique, ..settings.clone() };
                let l = label(backend.as_ref(), &s);
                on_step(&format!("{curve} curve: {name}, {technique} on {l}"));
                let timed = match &mut prepared {
                    Ok(p) => measure(p.as_mut(), &camera, &s, (1, config.warmup_ms), curves.frames),
                    Err(e) => Err(OitError::InvalidSettings(e.to_string())),
                };
                match timed {
                    Ok(t) => report.curves.push(CurvePoint {
                        curve: curve.into(),
                        scene: name.clone(),
                        backend: l,
                        technique: technique.to_string(),
                        x,
                        time_ms: time_of(&t.wall, &t.gpu).0,
                        passes: t.frame.stats.geometry_passes,
                        fragments: t.frame.stats.fragments,
                    }),
                    Err(e) => fail(
                        report,
                        &format!("{curve} curve"),
                        &name,
                        &l,
                        &technique.to_string(),
                        &e.to_string(),
                    ),
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod cross_check_tests {
    use super::*;

    fn image(pixels: Vec<[u8; 4]>) -> Image {
        Image { width: pixels.len() as u32, height: 1, pixels }
    }

    /// The bench's matrix check fails on a skewed colour, off the edges, and only there.
    #[test]
    fn cross_check_fails_on_a_skew_off_the_edges() {
        let a = image(vec![[100, 100, 100, 255]; 4]);
        let mut b = a.clone();
        let edges = [true, false, false, false];
        let t = Technique::Fabs { k: None };
        let check = |b: &Image, raster| {
            let sa = Side { label: "cpu", raster: RasterPath::Cpu, image: &a, lost: 0 };
            let sb = Side { label: "other", raster, image: b, lost: 0 };
            cross_check(t, &sa, &sb, &edges)
        };
        assert!(!check(&b, RasterPath::Compute).2);
        b.pixels[0][1] = 140; // on an edge: a hardware rasterizer may differ there, oit's rules may not
        assert!(!check(&b, RasterPath::Hardware).2);
        assert!(check(&b, RasterPath::Compute).2);
        b.pixels[0][1] = 100;
        b.pixels[2][2] = 102; // off the edges, 2 steps: fails on every path
        assert!(check(&b, RasterPath::Hardware).2);
        assert!(check(&b, RasterPath::Compute).2);
        b.pixels[2][2] = 101; // 1 step: float order
        assert!(!check(&b, RasterPath::Hardware).2);
    }

    /// Rows of different `--blend-targets` are not held to each other; rows of one target are.
    #[test]
    fn cross_check_holds_blend_targets_to_their_own() {
        let a = image(vec![[100, 100, 100, 255]; 2]);
        let b = image(vec![[100, 104, 100, 255]; 2]);
        let edges = [false; 2];
        let check = |x: &str, y: &str| {
            let sa = Side { label: x, raster: RasterPath::Hardware, image: &a, lost: 0 };
            let sb = Side { label: y, raster: RasterPath::Hardware, image: &b, lost: 0 };
            cross_check(Technique::Plain, &sa, &sb, &edges)
        };
        let (_, note, failed) = check("wgpu/hardware", "wgpu+unorm8/hardware");
        assert!(!failed && note.is_some_and(|n| n.contains("not held")));
        assert!(!check("wgpu+f16/hardware", "vulkan+unorm8/hardware").2);
        assert!(check("wgpu+unorm8/hardware", "vulkan+unorm8/hardware").2);
        assert!(check("wgpu+f16/hardware", "vulkan+f16/hardware").2);
        assert!(check("wgpu/hardware", "vulkan/hardware").2);
    }
}
