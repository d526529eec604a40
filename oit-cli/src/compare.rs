//! `oit compare`: every technique asked for against the reference, from one view.

use std::path::PathBuf;

use clap::Args;
use oit_bench::experiment::{Experiment, Measured, Measurement, Step};
use oit_bench::present::{SheetEntry, annotate_frame, contact_sheet};
use oit_core::metrics::{Accuracy, accuracy, error_image};
use oit_core::{Effect, Frame, Image, OitError, RasterPath, Settings, Stats, Technique};
use serde::Serialize;

use crate::Outcome;
use crate::options::{Prepared, SceneArgs, check_output};
use crate::output::{self, Table};

/// Arguments of `oit compare`.
#[derive(Args, Debug)]
#[command(
    about = "Render techniques from one view and measure each against the exact reference",
    long_about = "Render techniques from one view and measure each against the exact reference.\n\n\
        Renders `reference` once per backend, then every technique, and prints a table: geometry \
        passes, fragments, fragments captured, merged (into a pixel's tail, --overflow tail), \
        lost and occluded (behind the opaque geometry, drawn first), fragments tied (equal depths the technique ordered by \
        colour, not as the reference), fragments quantized (composited through a lossy packing of \
        their colour: bdp's colour mode keeps alpha in 7 bits, one 8-bit step off for half the \
        alphas; docs/bdp-colour.md gives the bound), per-pixel storage, time, error pixel rate (EPR: the \
        share of covered pixels off by more than 1 in 8 bits, in per cent) and PSNR (inf when \
        identical). A \
        technique that fails prints its error in its row and the others go on; the exit code is \
        then 1. With `-t all`, a technique the options refuse (an effect or capture it cannot do) \
        is listed after the table with the reason and the others run; the exit code is 1 only \
        when none ran. With --json, prints one JSON array of objects with the keys technique, backend, \
        raster, width, height, geometry_passes, fragments, captured, merged, lost, occluded, opaque_fragments, masked, tied, quantized, storage_bytes, \
        tiles, wall_ms, gpu_ms, epr, psnr, max_error (epr a fraction in [0, 1], not per cent; gpu_ms \
        null when not measured, psnr null when identical); failures go to stderr. With --samples \
        4|8 --supersample the EPR and PSNR are against the supersampled reference, a column `EPR \
        MSAA (%)` (JSON `epr_msaa`) gives each technique's error against the per-sample reference \
        (MSAA's target), and a row `msaa-ref` gives the per-sample reference's own error against \
        supersampling."
)]
pub struct CompareArgs {
    /// Comma-separated techniques (e.g. dp,bdp2,fabs:16), or all (`--help` lists the names).
    #[arg(short, long, value_name = "LIST|all", default_value = "all", long_help = techniques_help())]
    pub techniques: String,

    /// Print one JSON array of results instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Also write a contact sheet: the reference, then each technique beside its error image
    /// (×8, black where within 1/255), captioned with EPR, PSNR and fragments lost [default: none].
    #[arg(long, value_name = "FILE.png")]
    pub sheet: Option<PathBuf>,

    #[command(flatten)]
    pub scene: SceneArgs,
}

/// One row of `oit compare --json`: exactly these keys (and `gpu_pass_ms` where measured).
#[derive(Serialize)]
struct CompareJson<'a> {
    technique: String,
    backend: &'a str,
    raster: String,
    width: u32,
    height: u32,
    /// `geometry_passes`, `fragments`, `captured`, `lost`, `tied`, `quantized`, `storage_bytes`, `wall_ms`,
    /// `gpu_ms`, `max_layers`, `tiles`.
    #[serde(flatten)]
    stats: &'a Stats,
    /// Error pixel rate, a fraction in [0, 1] (the table prints it in per cent).
    epr: f64,
    psnr: Option<f64>,
    max_error: f64,
    /// With `--supersample`: the error pixel rate against the per-sample (MSAA) reference, where
    /// `epr` is against the supersampled one.
    #[serde(skip_serializing_if = "Option::is_none")]
    epr_msaa: Option<f64>,
}

const HEADERS: [(&str, usize); 16] = [
    ("technique", 10),
    ("backend", 7),
    ("raster", 8),
    ("passes", 6),
    ("fragments", 10),
    ("captured", 10),
    ("merged", 8),
    ("lost", 8),
    ("occluded", 8),
    ("tied", 8),
    ("quantized", 9),
    ("storage", 10),
    ("time (ms)", 9),
    ("GPU (ms)", 8),
    ("EPR (%)", 8),
    ("PSNR (dB)", 9),
];

/// A sheet row for something that failed: its label, a dark image and the error.
fn failed_row(label: String, message: &str, width: u32, height: u32) -> SheetEntry {
    SheetEntry {
        label,
        image: Image::new(width, height, [20, 20, 20, 255]),
        error: None,
        caption: format!("failed: {message}"),
    }
}

/// Every check `oit compare` makes before it renders: the technique list, the sheet's path,
/// then the scene options ([`SceneArgs::prepare`]). Reads, writes nothing.
pub fn check(args: &CompareArgs) -> Result<(Vec<Technique>, Prepared), OitError> {
    let techniques = Technique::parse_list(&args.techniques)?;
    if let Some(sheet) = &args.sheet {
        check_output(sheet, "png", "--sheet")?;
    }
    Ok((techniques, args.scene.prepare()?))
}

/// Runs `oit compare`.
pub fn run(args: &CompareArgs) -> Result<Outcome, OitError> {
    let (techniques, prepared) = check(args)?;
    let (width, height) = (prepared.settings.width, prepared.settings.height);
    // with --supersample the baseline is the supersampled reference; the per-sample one is
    // rendered too, so that each technique's error against MSAA's target and MSAA's own error
    // against supersampling come in one table
    let supersampled = oit_core::msaa::is_supersampled(&Settings {
        technique: Technique::Reference,
        ..prepared.settings.clone()
    });
    let per_sample = if supersampled { msaa_references(&prepared, &args.scene.scene)? } else { Vec::new() };
    let experiment = Experiment {
        backends: &prepared.backends,
        settings: &prepared.settings,
        techniques: &techniques,
        warmup: 0,
        warmup_ms: 0,
        frames: 1,
        keep_images: args.sheet.is_some() || supersampled,
    };

    let mut headers = HEADERS.to_vec();
    if supersampled {
        headers.push(("EPR MSAA (%)", 12));
    }
    let (table, header) = Table::new(&headers, 2);
    if !args.json {
        output::print(&header)?;
    }
    let (mut failures, mut attempts) = (0usize, 0usize);
    // `-t all` runs the catalogue: a technique these options refuse (an effect it cannot do, a
    // capture it has none of) is listed after the table with its reason, not counted as a failure
    let whole_catalogue = args.techniques.trim().eq_ignore_ascii_case("all");
    let mut refused: Vec<String> = Vec::new();
    let mut ran = 0usize;
    let mut printed = Ok(());
    let measurements = experiment.run(&args.scene.scene, &prepared.scene, &[prepared.view], &mut |step| {
        let Step::Measured(m) = step else { return };
        if m.baseline {
            attempts += techniques.len();
        }
        let technique = m.technique.to_string();
        let result = match &m.result {
            Ok(r) => r,
            Err(e) if whole_catalogue && m.refused && !m.baseline => {
                refused.push(format!("{technique} on {}: {e}", m.label()));
                return;
            }
            Err(e) => {
                // Without a reference nothing on this backend can be measured.
                failures += if m.baseline { techniques.len() } else { 1 };
                let shown = if m.baseline { "reference".to_string() } else { technique };
                if args.json {
                    output::error_line(&format!("{shown} on {}: {e}", m.backend));
                } else if printed.is_ok() {
                    printed = output::print(&table.note(&[shown, m.backend.clone()], &format!("error: {e}")));
                }
                return;
            }
        };
        let msaa = per_sample.get(m.backend_index).and_then(Option::as_ref);
        if m.baseline && !args.json && printed.is_ok() {
            // the per-sample reference against the supersampled one: MSAA's own error
            if let (Some(r), Some(ss)) = (msaa, result.frame()) {
                printed = match accuracy(&ss, &r.image) {
                    Ok(acc) => output::print(&table.row(&msaa_row(r, &m.backend, m.raster, acc))),
                    Err(e) => Err(e),
                };
            }
        }
        let Some(acc) = result.accuracy else { return };
        ran += 1;
        let s = &result.stats;
        let epr_msaa = msaa.and_then(|r| Some(accuracy(r, result.image.as_ref()?).ok()?.epr));
        if !args.json && printed.is_ok() {
            let mut cells = row_cells(technique, &m.backend, m.raster, s, acc);
            if supersampled {
                cells.push(epr_msaa.map_or_else(|| "-".to_string(), output::percent));
            }
            printed = output::print(&table.row(&cells));
        }
    })?;
    printed?;
    if args.json {
        let rows: Vec<CompareJson<'_>> = measurements
            .iter()
            .filter(|m| !m.baseline)
            .filter_map(|m| {
                let r = m.result.as_ref().ok()?;
                let acc = r.accuracy?;
                Some(CompareJson {
                    technique: m.technique.to_string(),
                    backend: &m.backend,
                    raster: m.raster.to_string(),
                    width,
                    height,
                    stats: &r.stats,
                    epr: acc.epr,
                    psnr: acc.psnr.is_finite().then_some(acc.psnr),
                    max_error: acc.max_error,
                    epr_msaa: per_sample
                        .get(m.backend_index)
                        .and_then(Option::as_ref)
                        .and_then(|msaa| Some(accuracy(msaa, r.image.as_ref()?).ok()?.epr)),
                })
            })
            .collect();
        output::print_json(&rows)?;
    }
    if let Some(path) = &args.sheet {
        contact_sheet(&sheet_rows(&measurements, width, height, prepared.settings.effect)).save_png(path)?;
        if !args.json {
            output::print(&format!("wrote {}\n", path.display()))?;
        }
    }
    if !refused.is_empty() {
        let list = format!(
            "{} of the catalogue refused under these options (the others ran):\n{}\n",
            refused.len(),
            refused.iter().map(|r| format!("  {r}")).collect::<Vec<_>>().join("\n")
        );
        // with --json, stdout holds only the JSON
        if args.json {
            eprint!("{list}");
        } else {
            output::print(&list)?;
        }
    }
    if failures > 0 {
        output::error_line(&format!("{failures} of {attempts} technique runs failed"));
        return Ok(Outcome::Failed);
    }
    if ran == 0 && !refused.is_empty() {
        output::error_line("every technique was refused under these options; nothing ran");
        return Ok(Outcome::Failed);
    }
    Ok(Outcome::Success)
}

/// The per-sample reference (the MSAA target) of each backend of `prepared`, where the table's
/// baseline is the supersampled reference (`--supersample`); `None` where a backend could not
/// render it (its supersampled baseline then fails alike and says why).
fn msaa_references(prepared: &Prepared, scene: &str) -> Result<Vec<Option<Frame>>, OitError> {
    let settings = Settings { supersample: false, ..prepared.settings.clone() };
    let experiment = Experiment {
        backends: &prepared.backends,
        settings: &settings,
        techniques: &[],
        warmup: 0,
        warmup_ms: 0,
        frames: 1,
        keep_images: true,
    };
    let measured = experiment.run(scene, &prepared.scene, &[prepared.view], &mut |_| {})?;
    let mut frames = vec![None; prepared.backends.len()];
    for m in measured.iter().filter(|m| m.baseline) {
        frames[m.backend_index] = m.result.as_ref().ok().and_then(Measured::frame);
    }
    Ok(frames)
}

/// The table's row of the per-sample reference `r` measured against the supersampled one: its
/// EPR and PSNR are MSAA's own error, and it is its own MSAA target (0).
fn msaa_row(r: &Frame, backend: &str, raster: RasterPath, acc: Accuracy) -> Vec<String> {
    let mut cells = row_cells("msaa-ref".to_string(), backend, raster, &r.stats, acc);
    cells.push(output::percent(0.0));
    cells
}

/// A row's cells under [`HEADERS`]: what ran, its counters, its times and its accuracy.
fn row_cells(label: String, backend: &str, raster: RasterPath, s: &Stats, acc: Accuracy) -> Vec<String> {
    vec![
        label,
        backend.to_string(),
        raster.to_string(),
        s.geometry_passes.to_string(),
        s.fragments.to_string(),
        s.captured.to_string(),
        s.merged.to_string(),
        s.lost.to_string(),
        s.occluded.to_string(),
        s.tied.to_string(),
        s.quantized.to_string(),
        output::bytes(s.storage_bytes),
        format!("{:.2}", s.wall_ms),
        s.gpu_ms.map_or_else(|| "-".to_string(), |g| format!("{g:.2}")),
        output::percent(acc.epr),
        output::psnr(acc.psnr),
    ]
}

/// The contact sheet's rows: per backend, its reference, then each technique beside its error
/// image (a failure as a dark image with its message).
fn sheet_rows(measurements: &[Measurement], width: u32, height: u32, effect: Effect) -> Vec<SheetEntry> {
    let mut rows = Vec::new();
    let mut reference: Option<Frame> = None;
    for m in measurements {
        let name = &m.backend;
        let label =
            if m.baseline { format!("reference ({name})") } else { format!("{} ({name})", m.technique) };
        let (r, frame) = match (&m.result, m.result.as_ref().ok().and_then(Measured::frame)) {
            (Ok(r), Some(frame)) => (r, frame),
            (result, _) => {
                let message = result.as_ref().err().map_or("no image kept", String::as_str);
                if m.baseline {
                    reference = None;
                }
                rows.push(failed_row(label, message, width, height));
                continue;
            }
        };
        let s = &r.stats;
        let mut image = frame.image.clone();
        annotate_frame(&mut image, effect, s);
        if m.baseline {
            rows.push(SheetEntry {
                label,
                image,
                error: None,
                caption: format!("{} fragments, {:.1} ms", s.fragments, s.wall_ms),
            });
            reference = Some(frame);
            continue;
        }
        let (Some(reference), Some(acc)) = (&reference, r.accuracy) else { continue };
        rows.push(SheetEntry {
            label,
            error: Some(error_image(reference, &frame.image)),
            caption: format!(
                "EPR {}%  PSNR {} dB  lost {}  tied {}",
                output::percent(acc.epr),
                output::psnr(acc.psnr),
                s.lost,
                s.tied
            ),
            image,
        });
    }
    rows
}

/// `--techniques`' long help, its names from the catalogue ([`oit_core::KNOWN_TECHNIQUES`]).
fn techniques_help() -> String {
    format!(
        "Comma-separated techniques (e.g. dp,bdp2,fabs:16), or all (every technique but the \
         reference and kbuf, in catalogue order). Names: {} (kbuf: vulkan's hardware path on a \
         device with fragment shader interlock)",
        oit_core::KNOWN_TECHNIQUES
    )
}
