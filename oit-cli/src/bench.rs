//! `oit bench`: the speed/accuracy report (oit-bench's `run_bench`) written into a folder.

use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use oit_bench::model::CPU_CALIBRATION;
use oit_bench::{Config, CurveConfig, MAX_CURVE_DEPTH, MAX_FRAMES, ModelFile};
use oit_core::{OitError, Technique};

use crate::Outcome;
use crate::options::SceneArgs;
use crate::output;

/// What `oit bench` measures when neither `--scenes` nor `--scene` names scenes: the real-content
/// scene set (docs/scenes.md), the cases order-independent transparency exists for, and the
/// untextured bunny the earlier tables were measured on.
pub const BENCH_SCENES: &str = "particles,foliage,glass,cad,bunny";

/// Arguments of `oit bench`.
#[derive(Args, Debug)]
#[command(
    about = "Time every technique on every backend and write the speed/accuracy report",
    long_about = "Time every technique on every backend and write the speed/accuracy report.\n\n\
        For each scene × backend (× raster path) × technique: --warmup untimed frames, then \
        --frames timed steady-state frames (the same prepared scene, no image readback) and \
        --frames timed frames with their image read back; the median and spread of GPU \
        milliseconds, steady-state wall milliseconds and wall milliseconds with the readback, passes, \
        fragments, lost, storage, Gfrag/s, and EPR (error pixel rate: in per cent in report.md \
        and the plots, a fraction in [0, 1] in report.json) and PSNR against the same backend's \
        reference. \
        Then the trade plot (time vs EPR, log axes, the Pareto front), the cost model's \
        check (each technique's time and speedup over dp predicted from the scene's statistics by \
        a per-device calibration, --calibrate, beside the measured ones; its error on scenes it \
        was not calibrated on), the cross-backend matrix, and two \
        curves: time vs depth complexity (planes:N, N = 1, 2, 4, ..., 256) and time vs triangles \
        (grid:RxC:MESH). Writes report.md, report.json and the plots (SVG and PNG) into --out. \
        A progress bar goes to stderr; a run that fails is listed in the report and the exit \
        code is then 1. Use --backend all (or --raster all) for one row per backend and raster path. \
        Every option (scenes, technique lists, sizes, the curves' mesh) is checked before anything \
        is measured."
)]
pub struct BenchArgs {
    /// Comma-separated scenes (built-in names, grid:RxC:MESH, or .obj/.gltf/.glb paths) [default:
    /// the scene set particles,foliage,glass,cad and the bunny; the --scene value where one other
    /// than `default` is given].
    #[arg(long, value_name = "LIST")]
    pub scenes: Option<String>,

    /// Comma-separated techniques (e.g. dp,bdp2,fabs:16), or all (every technique but the
    /// reference, which is rendered anyway for accuracy).
    #[arg(short, long, value_name = "LIST|all", default_value = "all")]
    pub techniques: String,

    /// Timed frames per run (medians want 10 or more): in a frame loop without the image's
    /// readback (the steady state; frames in flight where the backend keeps them), one at a time
    /// without it (the latency; only where the loop kept frames in flight), and with it.
    #[arg(long, value_name = "N", default_value_t = 10)]
    pub frames: u32,

    /// Untimed warm-up frames per run, before the timed ones.
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub warmup: u32,

    /// After the warm-up frames, untimed frame loops for at least this many milliseconds per
    /// row: a GPU that idled between rows clocks down, and a few frames do not bring it back.
    #[arg(long, value_name = "MS", default_value_t = 0)]
    pub warmup_ms: u32,

    /// Folder for report.md, report.json and the plots (made if missing).
    #[arg(long, value_name = "DIR", default_value = "bench-report")]
    pub out: PathBuf,

    /// The mesh of the triangle curve's grid:RxC:MESH scenes: a built-in scene (bunny, armadillo,
    /// knot, ...), an .obj path, or a bare name looked up as NAME.obj in $OIT_MODELS, then models/.
    #[arg(long, value_name = "MESH", default_value = "knot")]
    pub curves: String,

    /// Draw an earlier run again: read DIR/report.json and rewrite report.md and the plots in
    /// DIR, measuring nothing (the other options are ignored).
    #[arg(long, value_name = "DIR")]
    pub replot: Option<PathBuf>,

    /// Skip the two curves.
    #[arg(long)]
    pub no_curves: bool,

    /// Narrower blend targets measured beside the default on the hardware path, e.g. f16,unorm8:
    /// rows NAME+f16 (plain, and wavg/wsum by blending) and NAME+unorm8 (plain).
    #[arg(long, value_name = "LIST", default_value = "")]
    pub blend_targets: String,

    /// Techniques drawn on the curves.
    #[arg(long, value_name = "LIST", default_value = "dp,bdp,adp,fabs,mdts64")]
    pub curve_techniques: String,

    /// Image size of the curves' frames, WIDTHxHEIGHT (planes:256 with dp is 257 passes).
    #[arg(long, value_name = "WxH", default_value = "128x128")]
    pub curve_size: String,

    /// Largest N of the depth curve's planes:N (N = 1, 2, 4, ... up to it; 1 to 65536).
    #[arg(long, value_name = "N", default_value_t = 256)]
    pub curve_depth: u32,

    /// The R×C of the triangle curve's grid scenes, comma-separated.
    #[arg(long, value_name = "LIST", default_value = "1x1,1x2,2x2,2x4,4x4")]
    pub curve_grids: String,

    /// Timed frames per curve point (after one untimed).
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub curve_frames: u32,

    #[command(flatten)]
    pub cost: Box<ModelArgs>,

    #[command(flatten)]
    pub scene: SceneArgs,
}

/// The cost model's options of `oit bench` (boxed: they would make every command's arguments
/// larger).
#[derive(Args, Debug)]
pub struct ModelArgs {
    /// Calibrate the cost model on this device instead: time every technique on the procedural
    /// calibration scenes (--scenes replaces them; procedural scenes only), fit each backend/path ×
    /// technique, and write DIR/calibration.json (with the fit's residuals) beside the report of
    /// the calibration runs. The curves are skipped.
    #[arg(long)]
    pub calibrate: bool,

    /// The cost model to check: a calibration.json written by --calibrate [default: the shipped
    /// CPU calibration, for the cpu backend].
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,

    /// A note recorded in the calibration (e.g. that the machine was loaded).
    #[arg(long, value_name = "TEXT")]
    pub note: Option<String>,
}

/// What `oit bench` will do, every option checked.
pub enum Checked {
    /// Redraw the report read from this folder (`--replot`).
    Replot(PathBuf, oit_bench::Report),
    /// Measure: the bench's configuration.
    Measure(Config),
}

/// Every check `oit bench` makes before any work: with `--replot` the report read back and its
/// numbers; otherwise every option, every scene and the curves. Reads, writes nothing.
pub fn check(args: &BenchArgs) -> Result<Checked, OitError> {
    if let Some(dir) = &args.replot {
        return Ok(Checked::Replot(dir.clone(), oit_bench::read_report(dir)?));
    }
    // Every option is checked before any work: the cheap ones first, then (once the settings are
    // parsed and the backends open) every scene and the curves, then the output folder.
    let techniques = Technique::parse_list(&args.techniques)?;
    let frames = |n: u32, least: u32, option: &str| {
        if (least..=MAX_FRAMES).contains(&n) {
            Ok(())
        } else {
            Err(OitError::InvalidSettings(format!(
                "{option} {n} is out of range: use {least} to {MAX_FRAMES}"
            )))
        }
    };
    frames(args.frames, 1, "--frames")?;
    frames(args.warmup, 0, "--warmup")?;
    frames(args.curve_frames, 1, "--curve-frames")?;
    let list = |list: &str| -> Vec<String> {
        list.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect()
    };
    let scenes: Vec<String> = match &args.scenes {
        Some(l) => list(l),
        None if args.cost.calibrate => list(oit_bench::model::CALIBRATION_SCENES),
        None if args.scene.scene == oit_core::DEFAULT_SCENE => list(BENCH_SCENES),
        None => vec![args.scene.scene.clone()],
    };
    if args.cost.calibrate
        && let Some(s) = scenes.iter().find(|s| !oit_core::is_procedural(s))
    {
        return Err(OitError::InvalidSettings(format!(
            "--calibrate: scene {s} is not procedural; calibrate on procedural scenes only (planes:N, \
                 spheres:N, cluster:N, knot, and grid:RxC: of those), so that the meshes stay unseen \
                 for the check"
        )));
    }
    let (model, model_source) = match &args.cost.model {
        Some(path) => {
            let text = crate::render::read_calibration(path, "--model")?;
            let name = path.display().to_string();
            (Some(ModelFile::parse(&text, &name)?), Some(name))
        }
        None => {
            let shipped = ModelFile::parse(CPU_CALIBRATION, "the shipped CPU calibration")?;
            let source = "bench/results/cpu/calibration.json (shipped with oit-bench)".to_string();
            (Some(shipped).filter(|m| !m.calibrations.is_empty()), Some(source))
        }
    };
    let Some(first) = scenes.first() else {
        return Err(OitError::InvalidSettings("--scenes names no scene".into()));
    };
    if args.out.exists() && !args.out.is_dir() {
        return Err(OitError::Write { path: args.out.clone(), message: "--out must name a folder".into() });
    }
    let curves = if args.no_curves || args.cost.calibrate {
        None
    } else {
        if !(1..=MAX_CURVE_DEPTH).contains(&args.curve_depth) {
            return Err(OitError::InvalidSettings(format!(
                "--curve-depth {} is out of range: the depth curve renders planes:N for N = 1, 2, 4, ... \
                 up to it, so use 1 to {MAX_CURVE_DEPTH} (or --no-curves to skip the curves)",
                args.curve_depth
            )));
        }
        let (width, height) = oit_core::parse_size(&args.curve_size)
            .map_err(|e| OitError::InvalidSettings(format!("--curve-size: {e}")))?;
        let grids = args
            .curve_grids
            .split(',')
            .map(|g| {
                oit_core::parse_size(g.trim()).map_err(|_| {
                    OitError::InvalidSettings(format!("--curve-grids: '{g}' is not RxC (e.g. 2x4)"))
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let depths = (0..=16).map(|i| 1u32 << i).take_while(|&n| n <= args.curve_depth).collect();
        let techniques = Technique::parse_list(&args.curve_techniques)
            .map_err(|e| OitError::InvalidSettings(format!("--curve-techniques: {e}")))?;
        Some(CurveConfig {
            mesh: args.curves.clone(),
            techniques,
            depths,
            grids,
            width,
            height,
            frames: args.curve_frames,
        })
    };
    // the options checked and the backends opened on the first scene; the others load in turn
    let mut scene_args = args.scene.clone();
    scene_args.scene = first.clone();
    let prepared = scene_args.prepare()?;
    let blend_targets = args
        .blend_targets
        .split(',')
        .filter(|t| !t.trim().is_empty())
        .map(str::parse::<oit_core::BlendTarget>)
        .collect::<Result<Vec<_>, _>>()?;
    let config = Config {
        scenes,
        gltf_scene: args.scene.gltf_scene,
        backends: prepared.backends,
        settings: prepared.settings,
        view: prepared.view,
        techniques,
        warmup: args.warmup,
        warmup_ms: args.warmup_ms,
        frames: args.frames,
        curves,
        command_line: std::env::args().collect::<Vec<_>>().join(" "),
        model: if args.cost.calibrate { None } else { model },
        model_source,
        blend_targets,
    };
    config.validate()?;
    Ok(Checked::Measure(config))
}

/// Runs `oit bench`.
pub fn run(args: &BenchArgs) -> Result<Outcome, OitError> {
    let config = match check(args)? {
        Checked::Replot(dir, mut report) => {
            report.files.clear();
            oit_bench::write_report(&mut report, &dir)?;
            output::print(&format!(
                "redrew {} ({} files)\n",
                dir.join("report.md").display(),
                report.files.len()
            ))?;
            return Ok(Outcome::Success);
        }
        Checked::Measure(config) => config,
    };
    std::fs::create_dir_all(&args.out)
        .map_err(|e| OitError::Write { path: args.out.clone(), message: e.to_string() })?;
    let bar = ProgressBar::new(config.steps());
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} bench [{bar:30}] {pos}/{len} runs, {elapsed} (eta {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let mut first_step = true;
    let result = oit_bench::run_bench_with(&config, &mut |message| {
        if !first_step {
            bar.inc(1);
        }
        first_step = false;
        bar.set_message(message.to_string());
    });
    bar.finish_and_clear();
    let mut report = result?;
    if args.cost.calibrate {
        let path = args.out.join("calibration.json");
        let samples = oit_bench::samples(&report);
        let devices = report.backends.iter().map(|b| (b.label.clone(), b.device.clone())).collect();
        let model = ModelFile {
            host: report.host.clone(),
            commit: oit_bench::model::commit(),
            command_line: report.command_line.clone(),
            scenes: config.scenes.clone(),
            frames: config.frames,
            note: args.cost.note.clone(),
            calibrations: oit_bench::model::calibrate(&samples, &devices, (report.width, report.height)),
        };
        let json = serde_json::to_string_pretty(&model)
            .map_err(|e| OitError::Write { path: path.clone(), message: e.to_string() })?;
        std::fs::write(&path, json + "\n")
            .map_err(|e| OitError::Write { path: path.clone(), message: e.to_string() })?;
        // the report of the calibration runs shows the fit against them
        report.model_source = Some(path.display().to_string());
        report.predictions = oit_bench::model::predict(&model, &samples);
        output::print(&format!("wrote {}\n", path.display()))?;
        for c in &model.calibrations {
            for t in &c.techniques {
                output::print(&format!(
                    "{} {}: rms relative residual {:.1} %\n",
                    c.backend,
                    t.technique,
                    t.rms_relative * 100.0
                ))?;
            }
        }
    }
    oit_bench::write_report(&mut report, &args.out)?;
    for m in &report.model_summary {
        output::print(&format!(
            "model on {} ({} predictions on unseen scenes): median error {:.1} %, worst {} {:.1} % ({:.2}× off){}\n",
            m.backend,
            m.predictions,
            m.median_error * 100.0,
            m.worst_technique,
            m.worst_error * 100.0,
            m.worst_factor,
            if m.within_targets { "" } else { "; targets missed" }
        ))?;
    }
    // `-t all` runs the catalogue: what these options refuse is listed, not a failure
    let whole_catalogue = args.techniques.trim().eq_ignore_ascii_case("all");
    let (refused, failures): (Vec<_>, Vec<_>) =
        report.failures.iter().partition(|f| whole_catalogue && f.refused);
    for f in &failures {
        output::error_line(&format!(
            "{} {} on {} ({}): {}",
            f.stage, f.technique, f.backend, f.scene, f.error
        ));
    }
    if !refused.is_empty() {
        let lines: Vec<String> = refused
            .iter()
            .map(|f| format!("  {} on {} ({}): {}", f.technique, f.backend, f.scene, f.error))
            .collect();
        output::print(&format!(
            "{} of the catalogue refused under these options (the others ran; listed in the report):\n{}\n",
            refused.len(),
            lines.join("\n")
        ))?;
    }
    output::print(&format!(
        "{} runs measured; wrote {} ({} files)\n",
        report.rows.len(),
        args.out.join("report.md").display(),
        report.files.len()
    ))?;
    if !failures.is_empty() {
        output::error_line(&format!("{} run(s) failed; they are listed in the report", failures.len()));
        return Ok(Outcome::Failed);
    }
    if report.rows.is_empty() && !refused.is_empty() {
        output::error_line("every technique was refused under these options; nothing ran");
        return Ok(Outcome::Failed);
    }
    Ok(Outcome::Success)
}
