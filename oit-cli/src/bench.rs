//! `oit bench`: the speed/accuracy report (oit-bench's `run_bench`) written into a folder.

use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use oit_bench::{Config, CurveConfig, MAX_CURVE_DEPTH, MAX_FRAMES};
use oit_core::{OitError, Technique};

use crate::Outcome;
use crate::options::SceneArgs;
use crate::output;

/// Arguments of `oit bench`.
#[derive(Args, Debug)]
#[command(
    about = "Time every technique on every backend and write the speed/accuracy report",
    long_about = "Time every technique on every backend and write the speed/accuracy report.\n\n\
        For each scene × backend (× raster path) × technique: --warmup untimed frames, then \
        --frames timed ones; the median and spread of wall and GPU milliseconds, passes, \
        fragments, lost, storage, Gfrag/s, and EPR and PSNR against the same backend's reference. \
        Then the trade plot (time vs EPR, log axes, the Pareto front), the speedup model \
        (K = N·Tv/(Tv+Tf) beside the measured speedup over dp), the cross-backend matrix, and two \
        curves: time vs depth complexity (planes:N, N = 1, 2, 4, ..., 256) and time vs triangles \
        (grid:RxC:MESH). Writes report.md, report.json and the plots (SVG and PNG) into --out. \
        A progress bar goes to stderr; a run that fails is listed in the report and the exit \
        code is then 1. Use --backend all (or --raster all) for one row per backend and raster path. \
        Every option (scenes, technique lists, sizes, the curves' mesh) is checked before anything \
        is measured."
)]
pub struct BenchArgs {
    /// Comma-separated scenes (built-in names, grid:RxC:MESH, or .obj paths) [default: the
    /// --scene value].
    #[arg(long, value_name = "LIST")]
    pub scenes: Option<String>,

    /// Comma-separated techniques (e.g. dp,bdp2,fabs:16), or all (every technique but the
    /// reference, which is rendered anyway for accuracy).
    #[arg(short, long, value_name = "LIST|all", default_value = "all")]
    pub techniques: String,

    /// Timed frames per run (medians want 10 or more).
    #[arg(long, value_name = "N", default_value_t = 10)]
    pub frames: u32,

    /// Untimed warm-up frames per run, before the timed ones.
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub warmup: u32,

    /// Folder for report.md, report.json and the plots (made if missing).
    #[arg(long, value_name = "DIR", default_value = "bench-report")]
    pub out: PathBuf,

    /// The mesh of the triangle curve's grid:RxC:MESH scenes: a built-in scene, an .obj path, or
    /// a bare name looked up as NAME.obj in $OIT_MODELS, models/, ../shared/models/.
    #[arg(long, value_name = "MESH", default_value = "knot")]
    pub curves: String,

    /// Draw an earlier run again: read DIR/report.json and rewrite report.md and the plots in
    /// DIR, measuring nothing (the other options are ignored).
    #[arg(long, value_name = "DIR")]
    pub replot: Option<PathBuf>,

    /// Skip the two curves.
    #[arg(long)]
    pub no_curves: bool,

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
    pub scene: SceneArgs,
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
    let scenes: Vec<String> = match &args.scenes {
        Some(list) => list.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect(),
        None => vec![args.scene.scene.clone()],
    };
    let Some(first) = scenes.first() else {
        return Err(OitError::InvalidSettings("--scenes names no scene".into()));
    };
    if args.out.exists() && !args.out.is_dir() {
        return Err(OitError::Write { path: args.out.clone(), message: "--out must name a folder".into() });
    }
    let curves = if args.no_curves {
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
    let config = Config {
        scenes,
        backends: prepared.backends,
        settings: prepared.settings,
        view: prepared.view,
        techniques,
        warmup: args.warmup,
        frames: args.frames,
        curves,
        command_line: std::env::args().collect::<Vec<_>>().join(" "),
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
    oit_bench::write_report(&mut report, &args.out)?;
    for f in &report.failures {
        output::error_line(&format!(
            "{} {} on {} ({}): {}",
            f.stage, f.technique, f.backend, f.scene, f.error
        ));
    }
    output::print(&format!(
        "{} runs measured; wrote {} ({} files)\n",
        report.rows.len(),
        args.out.join("report.md").display(),
        report.files.len()
    ))?;
    if !report.failures.is_empty() {
        output::error_line(&format!(
            "{} run(s) failed; they are listed in the report",
            report.failures.len()
        ));
        return Ok(Outcome::Failed);
    }
    Ok(Outcome::Success)
}
