//! `oit render`: one technique, one image, its numbers.

use std::path::{Path, PathBuf};

use clap::Args;
use oit_bench::present::annotate_frame;
use oit_core::{OitError, Technique};
use serde::Serialize;

use crate::Outcome;
use crate::options::{SceneArgs, check_output};
use crate::output::{self, CameraJson, StatsJson};

/// Arguments of `oit render`.
#[derive(Args, Debug)]
#[command(
    about = "Render the scene with one technique and write a PNG",
    long_about = "Render the scene with one technique and write a PNG.\n\n\
        Prints the frame's numbers: geometry passes, fragments generated, captured and lost, \
        per-pixel storage and time. With --effect complexity the heat map gets its legend \
        (fragments per pixel, from 1 to the frame's most) in the bottom-right corner. With --json, prints one JSON object with those numbers, the \
        image size and the camera (view and projection matrices, eye, planes, angles), so another \
        renderer can reproduce the view. With several backends (--backend all), each writes its \
        own PNG, named FILE-BACKEND.png, and --json prints one object per line."
)]
pub struct RenderArgs {
    /// The technique: reference, dp, ddp, wavg, wsum, bdp, bdp:P, bdp2, adp, mdts[:K], mdts64[:K],
    /// fabs[:K] or mlp:M (K, M, P from 1 to 65536; K left out is sized from the scene).
    #[arg(short, long, value_name = "T", default_value = "reference")]
    pub technique: String,

    /// Where to write the image (PNG, sRGB).
    #[arg(short, long, value_name = "FILE.png", default_value = "oit.png")]
    pub output: PathBuf,

    /// Print one JSON object instead of the human-readable summary.
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub scene: SceneArgs,
}

/// `oit render --json`.
#[derive(Serialize)]
struct RenderJson<'a> {
    technique: String,
    backend: &'a str,
    raster: String,
    scene: &'a str,
    width: u32,
    height: u32,
    #[serde(flatten)]
    stats: StatsJson,
    /// Device milliseconds per pass label (geometry, and each kernel), where measured.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    gpu_pass_ms: Vec<(String, f64)>,
    output: &'a Path,
    camera: CameraJson,
}

/// `FILE.png` for one backend, `FILE-BACKEND.png` for each of several.
fn output_path(base: &Path, backend: &str, several: bool) -> PathBuf {
    if !several {
        return base.to_path_buf();
    }
    let stem = base.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "oit".into());
    let ext = base.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_else(|| "png".into());
    base.with_file_name(format!("{stem}-{backend}.{ext}"))
}

/// Runs `oit render`.
pub fn run(args: &RenderArgs) -> Result<Outcome, OitError> {
    let technique: Technique = args.technique.parse()?;
    check_output(&args.output, "png", "--output")?;
    let prepared = args.scene.prepare()?;
    let camera = prepared.camera(prepared.view)?;
    let settings = prepared.with_technique(technique);
    let several = prepared.backends.len() > 1;
    for backend in &prepared.backends {
        let mut frame = backend.render(&prepared.scene, &camera, &settings)?;
        let path = output_path(&args.output, backend.name(), several);
        annotate_frame(&mut frame.image, settings.effect, &frame.stats);
        frame.image.save_png(&path)?;
        let raster = output::raster_name(backend.as_ref(), &settings);
        let s = &frame.stats;
        if args.json {
            let json = RenderJson {
                technique: technique.to_string(),
                backend: backend.name(),
                raster,
                scene: &args.scene.scene,
                width: settings.width,
                height: settings.height,
                stats: StatsJson::from(s),
                gpu_pass_ms: s.gpu_pass_ms.clone(),
                output: &path,
                camera: CameraJson::new(&camera, prepared.view),
            };
            let text = serde_json::to_string(&json)
                .map_err(|e| OitError::Write { path: "standard output".into(), message: e.to_string() })?;
            output::print(&(text + "\n"))?;
        } else {
            let lost_share = if s.fragments > 0 { s.lost as f64 / s.fragments as f64 } else { 0.0 };
            let gpu = s.gpu_ms.map(|g| format!(", {g:.2} ms on the device")).unwrap_or_default();
            let text = format!(
                "technique  {technique}\n\
                 backend    {} (raster {raster})\n\
                 scene      {} ({} triangles)\n\
                 size       {}x{}\n\
                 passes     {}\n\
                 fragments  {}\n\
                 captured   {}\n\
                 lost       {} ({}%)\n\
                 storage    {}\n\
                 time       {:.2} ms{gpu}\n\
                 wrote      {}\n",
                backend.name(),
                args.scene.scene,
                prepared.scene.triangle_count(),
                settings.width,
                settings.height,
                s.geometry_passes,
                s.fragments,
                s.captured,
                s.lost,
                output::percent(lost_share),
                output::bytes(s.storage_bytes),
                s.wall_ms,
                path.display(),
            );
            output::print(&text)?;
        }
    }
    Ok(Outcome::Success)
}
