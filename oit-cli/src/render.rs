//! `oit render`: one technique, one image, its numbers.

use std::path::{Path, PathBuf};

use clap::Args;
use oit_bench::auto::{Budget, Choice, Tables, parse_max_epr};
use oit_bench::model::ModelFile;
use oit_bench::present::annotate_frame;
use oit_core::metrics::DepthComplexity;
use oit_core::{OitError, Stats, Technique};
use serde::Serialize;

use crate::Outcome;
use crate::options::{Prepared, SceneArgs, check_output};
use crate::output::{self, CameraJson};

/// Arguments of `oit render`.
#[derive(Args, Debug)]
#[command(
    about = "Render the scene with one technique and write a PNG",
    long_about = "Render the scene with one technique and write a PNG.\n\n\
        Prints the frame's numbers: geometry passes, fragments generated, captured, merged (into a \
        pixel's tail, with --overflow tail), lost and tied, \
        per-pixel storage, screen tiles and time. With --json, prints one JSON object with those \
        numbers, the image size, the camera (view and projection matrices, eye, planes, angles), so \
        another renderer can reproduce the view, and the depth complexity: `max_depth` (the \
        deepest pixel's fragments) and `depth_histogram` (pixels with 0, 1, 2, ... fragments), \
        from the reference's per-pixel counts (for another technique, one reference frame more \
        is rendered on the same backend to count them). With several backends or raster paths (--backend all, \
        --raster all), each writes its own PNG, named FILE-BACKEND.png or FILE-BACKEND-PATH.png \
        (e.g. out-cpu.png, out-wgpu-hardware.png, out-wgpu-compute.png; a note on stderr lists \
        them), and --json prints one object per line.\n\n\
        --technique auto chooses the technique and its parameters for this scene and device: one \
        counting pass gives the scene's depth histogram, each candidate gets an upper bound on its \
        error pixel rate from it, its storage, and a predicted time from the device's cost table \
        (`oit bench --calibrate`; --calibration FILE, else the shipped CPU and H200 tables); the \
        cheapest within --max-epr and --memory is rendered. --json's `auto` says what was picked \
        and why, every candidate with its prediction, bound, storage and any reason it was refused \
        (docs/auto.md).\n\n\
        --no-output writes no image, for runs that only want the numbers."
)]
pub struct RenderArgs {
    /// The technique, by name (`--help` lists them), or auto.
    #[arg(short, long, value_name = "T", default_value = "reference", long_help = technique_help())]
    pub technique: String,

    /// With --technique auto: the largest error pixel rate allowed, a fraction from 0 to 1 (0.001)
    /// or a percentage (0.1%); 0 picks an exact technique [default: 0].
    #[arg(long, value_name = "E", allow_negative_numbers = true)]
    pub max_epr: Option<String>,

    /// With --technique auto: the cost table, a calibration.json written by `oit bench
    /// --calibrate` [default: the shipped CPU calibration for cpu, the committed H200 one for
    /// wgpu; a backend/path neither has is ranked by the closest, and --json says so].
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,

    /// Where to write the image (PNG, sRGB).
    #[arg(short, long, value_name = "FILE.png", default_value = "oit.png")]
    pub output: PathBuf,

    /// Write no image, for runs that only want the numbers (the summary or --json, whose
    /// `output` is then null).
    #[arg(long, conflicts_with = "output")]
    pub no_output: bool,

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
    /// The frame's counters, under their own names (`geometry_passes`, `fragments`, ...,
    /// `gpu_pass_ms` where measured).
    #[serde(flatten)]
    stats: &'a Stats,
    /// The image written; null with `--no-output`.
    output: Option<&'a Path>,
    camera: CameraJson,
    /// The deepest pixel's fragments (from the reference's per-pixel counts).
    max_depth: u32,
    /// `depth_histogram[n]`: pixels with n fragments, n from 0 to `max_depth`.
    depth_histogram: &'a [u64],
    /// With `--technique auto`: what was picked and why.
    #[serde(skip_serializing_if = "Option::is_none")]
    auto: Option<&'a Choice>,
}

/// Largest `--calibration` file read (the committed ones are under 100 KiB).
const MAX_CALIBRATION_BYTES: u64 = 16 << 20;

/// The text of a calibration.json given to `option` (`--calibration`, `oit bench --model`):
/// refused unless a regular file of at most [`MAX_CALIBRATION_BYTES`], checked before it is
/// opened for reading (a FIFO would block in `open()`, issue 41.5).
pub fn read_calibration(path: &Path, option: &str) -> Result<String, OitError> {
    let io = |source| OitError::Io { path: path.to_path_buf(), source };
    let refuse = |what: &str| {
        OitError::InvalidSettings(format!(
            "{option} {} is not an oit calibration ({what}): expected a calibration.json written by \
             `oit bench --calibrate` (a regular file of at most {MAX_CALIBRATION_BYTES} bytes)",
            path.display()
        ))
    };
    let Some((file, meta)) = oit_core::open_regular(path).map_err(io)? else {
        return Err(refuse("not a regular file: a pipe, device or folder"));
    };
    if meta.len() > MAX_CALIBRATION_BYTES {
        return Err(refuse("too large"));
    }
    let mut text = String::new();
    std::io::Read::read_to_string(&mut std::io::Read::take(file, MAX_CALIBRATION_BYTES + 1), &mut text)
        .map_err(io)?;
    if text.len() as u64 > MAX_CALIBRATION_BYTES {
        return Err(refuse("too large"));
    }
    Ok(text)
}

/// What `--technique` asked for: one technique, or a choice under budgets.
pub enum Requested {
    /// The technique named.
    Fixed(Technique),
    /// `auto`: the budgets and the cost tables.
    Auto(Budget, Box<Tables>),
}

impl Requested {
    /// The technique, where one was named.
    pub fn fixed(&self) -> Option<Technique> {
        match self {
            Requested::Fixed(t) => Some(*t),
            Requested::Auto(..) => None,
        }
    }
}

/// Where each image goes: `FILE.png` when there is one; `FILE-LABEL.png` for each of several,
/// LABEL the backend and its raster path (`cpu`, `wgpu-hardware`, `wgpu-compute`), so that no
/// image overwrites another (a label met twice gets `-2`, `-3`, ...).
fn output_paths(base: &Path, labels: &[String]) -> Vec<PathBuf> {
    if labels.len() <= 1 {
        return vec![base.to_path_buf(); labels.len()];
    }
    let stem = base.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "oit".into());
    let ext = base.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_else(|| "png".into());
    let mut out: Vec<PathBuf> = Vec::new();
    for label in labels {
        let slug: String =
            label.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '-' }).collect();
        let mut path = base.with_file_name(format!("{stem}-{slug}.{ext}"));
        let mut n = 2;
        while out.contains(&path) {
            path = base.with_file_name(format!("{stem}-{slug}-{n}.{ext}"));
            n += 1;
        }
        out.push(path);
    }
    out
}

/// Every check `oit render` makes before it renders: the technique, the output path, then the
/// scene options ([`SceneArgs::prepare`]). Reads, writes nothing.
pub fn check(args: &RenderArgs) -> Result<(Requested, Prepared), OitError> {
    let requested = if args.technique.trim().eq_ignore_ascii_case("auto") {
        let max_epr = args.max_epr.as_deref().map(parse_max_epr).transpose()?.unwrap_or(0.0);
        let memory = args.scene.memory.as_deref().map(oit_core::parse_memory).transpose()?;
        let given = match &args.calibration {
            Some(path) => {
                // a calibration is a few kilobytes: refuse a device or a huge file before reading it
                let text = read_calibration(path, "--calibration")?;
                let name = path.display().to_string();
                Some((ModelFile::parse(&text, &name)?, name))
            }
            None => None,
        };
        Requested::Auto(Budget::new(max_epr, memory)?, Box::new(Tables::new(given)?))
    } else {
        for (flag, given) in
            [("--max-epr", args.max_epr.is_some()), ("--calibration", args.calibration.is_some())]
        {
            if given {
                return Err(OitError::InvalidSettings(format!(
                    "{flag} applies to --technique auto only (the technique named is '{}')",
                    args.technique
                )));
            }
        }
        Requested::Fixed(args.technique.parse()?)
    };
    if !args.no_output {
        check_output(&args.output, "png", "--output")?;
    }
    Ok((requested, args.scene.prepare()?))
}

/// Runs `oit render`.
pub fn run(args: &RenderArgs) -> Result<Outcome, OitError> {
    let (requested, prepared) = check(args)?;
    let camera = prepared.camera(prepared.view)?;
    // auto is labelled by the backend's default path for the reference (its counting pass)
    let labelled = prepared.with_technique(requested.fixed().unwrap_or(Technique::Reference));
    let labels: Vec<String> =
        prepared.backends.iter().map(|b| oit_bench::label(b.as_ref(), &labelled)).collect();
    let paths = output_paths(&args.output, &labels);
    if paths.len() > 1 && !args.no_output {
        let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
        eprintln!("note: {} images, one per backend and raster path: {}", paths.len(), names.join(", "));
    }
    for (backend, path) in prepared.backends.iter().zip(&paths) {
        // auto: the counting pass and the choice, per backend; its counts are the depth complexity
        let (technique, choice, counted) = match &requested {
            Requested::Fixed(t) => (*t, None, None),
            Requested::Auto(budget, tables) => {
                let (choice, frame) = oit_bench::auto::resolve(
                    backend.as_ref(),
                    &prepared.scene,
                    &camera,
                    &labelled,
                    tables,
                    *budget,
                )?;
                (choice.technique, Some(choice), Some(frame))
            }
        };
        let settings = prepared.with_technique(technique);
        let mut frame = backend.render(&prepared.scene, &camera, &settings)?;
        annotate_frame(&mut frame.image, settings.effect, &frame.stats);
        let written = (!args.no_output).then_some(path.as_path());
        if let Some(path) = written {
            frame.image.save_png(path)?;
        }
        let raster = backend.raster_path(&settings).to_string();
        let s = &frame.stats;
        if args.json {
            let depth = match &counted {
                Some(c) => depth_complexity(backend.as_ref(), &prepared.scene, &camera, &settings, c)?,
                None => depth_complexity(backend.as_ref(), &prepared.scene, &camera, &settings, &frame)?,
            };
            let json = RenderJson {
                technique: technique.to_string(),
                backend: backend.name(),
                raster,
                scene: &args.scene.scene,
                width: settings.width,
                height: settings.height,
                stats: s,
                output: written,
                camera: CameraJson::new(&camera, prepared.view),
                max_depth: depth.max_depth,
                depth_histogram: &depth.histogram,
                auto: choice.as_ref(),
            };
            let text = serde_json::to_string(&json)
                .map_err(|e| OitError::Write { path: "standard output".into(), message: e.to_string() })?;
            output::print(&(text + "\n"))?;
        } else {
            let lost_share = if s.fragments > 0 { s.lost as f64 / s.fragments as f64 } else { 0.0 };
            let gpu = s.gpu_ms.map(|g| format!(", {g:.2} ms on the device")).unwrap_or_default();
            let auto = choice
                .as_ref()
                .map(|c| format!("auto       {}\n           cost table: {}\n", c.reason, c.calibration))
                .unwrap_or_default();
            let text = format!(
                "technique  {technique}\n\
                 {auto}\
                 backend    {} (raster {raster})\n\
                 scene      {} ({} triangles)\n\
                 size       {}x{}\n\
                 passes     {}\n\
                 fragments  {}\n\
                 captured   {}\n\
                 merged     {}\n\
                 lost       {} ({}%)\n\
                 {}\
                 tied       {}\n\
                 storage    {}{}\n\
                 time       {:.2} ms{gpu}\n\
                 {}",
                backend.name(),
                args.scene.scene,
                prepared.scene.triangle_count(),
                settings.width,
                settings.height,
                s.geometry_passes,
                s.fragments,
                s.captured,
                s.merged,
                s.lost,
                output::percent(lost_share),
                if s.opaque_fragments > 0 {
                    format!(
                        "occluded   {} (behind the opaque pass's {} fragments, {} of them masked away)\n",
                        s.occluded, s.opaque_fragments, s.masked
                    )
                } else {
                    String::new()
                },
                s.tied,
                output::bytes(s.storage_bytes),
                if s.tiles > 1 {
                    format!(" (the largest of {} screen tiles)", s.tiles)
                } else {
                    String::new()
                },
                s.wall_ms,
                written.map(|p| format!("wrote      {}\n", p.display())).unwrap_or_default(),
            );
            output::print(&text)?;
        }
    }
    Ok(Outcome::Success)
}

/// The frame's depth complexity from per-pixel fragment counts: the frame's own where its
/// technique counted them (the reference), else a reference frame's on the same backend, path and
/// settings (memory budget included).
fn depth_complexity(
    backend: &dyn oit_core::Backend,
    scene: &oit_core::Scene,
    camera: &oit_core::Camera,
    settings: &oit_core::Settings,
    frame: &oit_core::Frame,
) -> Result<DepthComplexity, OitError> {
    if let Some(layers) = &frame.layers {
        return Ok(DepthComplexity::from_layers(layers));
    }
    let reference = oit_core::Settings { technique: Technique::Reference, ..settings.clone() };
    let counted = backend.render(scene, camera, &reference)?;
    let layers = counted.layers.ok_or_else(|| {
        OitError::Device(format!(
            "{}'s reference frame came back without its per-pixel counts",
            backend.name()
        ))
    })?;
    Ok(DepthComplexity::from_layers(&layers))
}

/// `--technique`'s long help, its names from the catalogue ([`oit_core::KNOWN_TECHNIQUES`]), so a
/// technique added there is listed here without an edit.
fn technique_help() -> String {
    format!(
        "The technique: {} (K, M, P from 1 to 65536; K left out is sized from the scene; dfb and \
         ll allocate exactly the frame's fragments, counted first; plain is unsorted alpha \
         blending in primitive order, the baseline; kbuf runs on --backend vulkan --raster \
         hardware on a device with fragment shader interlock), or auto (chosen for this scene and \
         device under --max-epr and --memory)",
        oit_core::KNOWN_TECHNIQUES
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_images_get_distinct_names() {
        let base = Path::new("dir/b.png");
        assert_eq!(output_paths(base, &["wgpu/compute".into()]), [PathBuf::from("dir/b.png")]);
        let labels: Vec<String> =
            ["cpu", "wgpu/hardware", "wgpu/compute", "wgpu/compute"].map(String::from).into();
        let names: Vec<PathBuf> = output_paths(base, &labels);
        assert_eq!(
            names,
            [
                "dir/b-cpu.png",
                "dir/b-wgpu-hardware.png",
                "dir/b-wgpu-compute.png",
                "dir/b-wgpu-compute-2.png"
            ]
            .map(PathBuf::from)
        );
    }
}
