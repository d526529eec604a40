//! `oit compare`: every technique asked for against the reference, from one view.

use std::path::PathBuf;

use clap::Args;
use oit_bench::present::{SheetEntry, annotate_frame, contact_sheet};
use oit_core::metrics::{accuracy, error_image};
use oit_core::{Frame, Image, OitError, Technique};
use serde::Serialize;

use crate::Outcome;
use crate::options::{SceneArgs, check_output};
use crate::output::{self, Table};

/// Arguments of `oit compare`.
#[derive(Args, Debug)]
#[command(
    about = "Render techniques from one view and measure each against the exact reference",
    long_about = "Render techniques from one view and measure each against the exact reference.\n\n\
        Renders `reference` once per backend, then every technique, and prints a table: geometry \
        passes, fragments, fragments lost, per-pixel storage, time, error pixel rate (EPR: the \
        share of covered pixels off by more than 1 in 8 bits) and PSNR (inf when identical). A \
        technique that fails prints its error in its row and the others go on; the exit code is \
        then 1. With --json, prints one JSON array of objects with the keys technique, backend, \
        raster, width, height, geometry_passes, fragments, captured, lost, storage_bytes, \
        wall_ms, gpu_ms, epr, psnr, max_error (gpu_ms null when not measured, psnr null when \
        identical); failures go to stderr."
)]
pub struct CompareArgs {
    /// Comma-separated techniques (e.g. dp,bdp2,fabs:16), or all (every technique but the
    /// reference, in catalogue order). Names: reference, dp, ddp, wavg, wsum, bdp, bdp:P, bdp2,
    /// adp, mdts[:K], mdts64[:K], fabs[:K], mlp:M.
    #[arg(short, long, value_name = "LIST|all", default_value = "all")]
    pub techniques: String,

    /// Print one JSON array of results instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Also write a contact sheet: a grid of the reference, then each technique beside its error
    /// image (×8, black where within 1/255), captioned above with EPR, PSNR and fragments lost
    /// [default: none].
    #[arg(long, value_name = "FILE.png")]
    pub sheet: Option<PathBuf>,

    #[command(flatten)]
    pub scene: SceneArgs,
}

/// One row of `oit compare --json`: exactly these keys.
#[derive(Serialize)]
struct CompareJson {
    technique: String,
    backend: String,
    raster: String,
    width: u32,
    height: u32,
    geometry_passes: u32,
    fragments: u64,
    captured: u64,
    lost: u64,
    storage_bytes: u64,
    wall_ms: f64,
    gpu_ms: Option<f64>,
    epr: f64,
    psnr: Option<f64>,
    max_error: f64,
}

const HEADERS: [(&str, usize); 11] = [
    ("technique", 10),
    ("backend", 7),
    ("raster", 8),
    ("passes", 6),
    ("fragments", 10),
    ("lost", 8),
    ("storage", 10),
    ("time (ms)", 9),
    ("GPU (ms)", 8),
    ("EPR (%)", 8),
    ("PSNR (dB)", 9),
];

/// A sheet cell for something that failed: its label, a dark image and the error.
fn failed_entry(label: String, message: &str, width: u32, height: u32) -> SheetEntry {
    SheetEntry {
        label,
        image: Image::new(width, height, [20, 20, 20, 255]),
        error: None,
        caption: format!("failed: {message}"),
    }
}

/// Runs `oit compare`.
pub fn run(args: &CompareArgs) -> Result<Outcome, OitError> {
    let techniques = Technique::parse_list(&args.techniques)?;
    if let Some(sheet) = &args.sheet {
        check_output(sheet, "png", "--sheet")?;
    }
    let prepared = args.scene.prepare()?;
    let camera = prepared.camera(prepared.view)?;
    let (width, height) = (prepared.settings.width, prepared.settings.height);

    let (table, header) = Table::new(&HEADERS, 2);
    if !args.json {
        output::print(&header)?;
    }
    let mut rows_json = Vec::new();
    let mut sheet = Vec::new();
    let (mut failures, mut attempts) = (0usize, 0usize);
    // Reports a failed technique: in its table row, or on stderr under --json.
    let fail = |technique: &str, backend: &str, e: &OitError| -> Result<(), OitError> {
        if args.json {
            output::error_line(&format!("{technique} on {backend}: {e}"));
            Ok(())
        } else {
            output::print(&table.note(&[technique.to_string(), backend.to_string()], &format!("error: {e}")))
        }
    };

    for backend in &prepared.backends {
        let name = backend.name();
        let ref_settings = prepared.with_technique(Technique::Reference);
        attempts += techniques.len();
        let reference: Frame = match backend.render(&prepared.scene, &camera, &ref_settings) {
            Ok(frame) => frame,
            Err(e) => {
                // Without a reference nothing on this backend can be measured.
                fail("reference", name, &e)?;
                failures += techniques.len();
                if args.sheet.is_some() {
                    sheet.push(failed_entry(format!("reference ({name})"), &e.to_string(), width, height));
                }
                continue;
            }
        };
        if args.sheet.is_some() {
            let s = &reference.stats;
            let mut image = reference.image.clone();
            annotate_frame(&mut image, ref_settings.effect, s);
            sheet.push(SheetEntry {
                label: format!("reference ({name})"),
                image,
                error: None,
                caption: format!("{} fragments, {:.1} ms", s.fragments, s.wall_ms),
            });
        }
        for &technique in &techniques {
            let label = technique.to_string();
            let settings = prepared.with_technique(technique);
            let result = backend
                .render(&prepared.scene, &camera, &settings)
                .and_then(|frame| Ok((accuracy(&reference, &frame.image)?, frame)));
            let (acc, frame) = match result {
                Ok(r) => r,
                Err(e) => {
                    failures += 1;
                    fail(&label, name, &e)?;
                    if args.sheet.is_some() {
                        sheet.push(failed_entry(format!("{label} ({name})"), &e.to_string(), width, height));
                    }
                    continue;
                }
            };
            let s = &frame.stats;
            if args.json {
                rows_json.push(CompareJson {
                    technique: label.clone(),
                    backend: name.to_string(),
                    raster: output::raster_name(backend.as_ref(), &settings),
                    width,
                    height,
                    geometry_passes: s.geometry_passes,
                    fragments: s.fragments,
                    captured: s.captured,
                    lost: s.lost,
                    storage_bytes: s.storage_bytes,
                    wall_ms: s.wall_ms,
                    gpu_ms: s.gpu_ms,
                    epr: acc.epr,
                    psnr: acc.psnr.is_finite().then_some(acc.psnr),
                    max_error: acc.max_error,
                });
            } else {
                output::print(&table.row(&[
                    label.clone(),
                    name.to_string(),
                    output::raster_name(backend.as_ref(), &settings),
                    s.geometry_passes.to_string(),
                    s.fragments.to_string(),
                    s.lost.to_string(),
                    output::bytes(s.storage_bytes),
                    format!("{:.2}", s.wall_ms),
                    s.gpu_ms.map_or_else(|| "-".to_string(), |g| format!("{g:.2}")),
                    output::percent(acc.epr),
                    output::psnr(acc.psnr),
                ]))?;
            }
            if args.sheet.is_some() {
                let error = Some(error_image(&reference, &frame.image));
                let mut image = frame.image;
                annotate_frame(&mut image, settings.effect, &frame.stats);
                sheet.push(SheetEntry {
                    label: format!("{label} ({name})"),
                    error,
                    caption: format!(
                        "EPR {}%  PSNR {} dB  lost {}",
                        output::percent(acc.epr),
                        output::psnr(acc.psnr),
                        s.lost
                    ),
                    image,
                });
            }
        }
    }
    if args.json {
        output::print_json(&rows_json)?;
    }
    if let Some(path) = &args.sheet {
        contact_sheet(&sheet).save_png(path)?;
        if !args.json {
            output::print(&format!("wrote {}\n", path.display()))?;
        }
    }
    if failures > 0 {
        output::error_line(&format!("{failures} of {attempts} technique runs failed"));
        return Ok(Outcome::Failed);
    }
    Ok(Outcome::Success)
}
