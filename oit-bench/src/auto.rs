//! `auto`: the technique and its parameters chosen for this scene and device, under an error
//! budget (`--max-epr`) and a memory budget (`--memory`), by the cost model ([`crate::model`]).
//!
//! One counting pass (the reference's per-pixel fragment counts on the same backend and path,
//! [`count`]) gives the scene's statistics ([`SceneStats`]: triangles, fragments, the per-pixel
//! depth histogram and its deepest pixel N). From them, every candidate gets, before it runs:
//!
//! - an **upper bound on its error pixel rate** ([`epr_bound`]), from the histogram alone: the
//!   share of covered pixels (the reference's pixels with a fragment) where the technique *can*
//!   differ from the reference. `dfb`, `ll` and `fabs` sized from the count keep every fragment
//!   and sort by (depth, primitive id) as the reference does: bound 0. `fabs:K` keeps the K
//!   nearest of each pixel (Liu et al. 2009; Huang et al. 2011): only pixels deeper than K can
//!   differ. The techniques that order equal depths by their payload (dp, ddp, mlp, mdts64), the
//!   order-free blends (wavg, wsum), bucket depth peeling (bdp, bdp2: a collision needs two
//!   fragments in one bucket; Liu et al., HPG 2009) and adp (two fragments in one of its 1024
//!   bins) are exact at a pixel of one fragment, so only pixels of two or more can differ.
//!   32-bit `mdts` stores one 8-bit alpha for every fragment and depth at 2⁻²⁰: no bound below
//!   every covered pixel (its documented worst case, 1), so it is a candidate only at
//!   `--max-epr 1`. The bounds are worst cases; the measured EPR is usually far lower.
//! - its **screen tiles and storage** under `--memory`, foreseen by the tiling loop the frame
//!   itself runs ([`oit_core::tiling::forecast`]: the same grid, the same refusals and splits,
//!   each window sized by [`Plan::frame_bytes`] with its part of the count, the backend's extra
//!   bytes a pixel and the stitched outputs beside it), so the tiles and the largest tile's
//!   storage `auto` reports are the ones the frame runs and reports, not a bound (held by
//!   oit-bench's `tests/forecast.rs`, `predicted_tiles_and_storage_are_the_frames`). Each
//!   further tile sets the whole scene up again: the prediction adds those repeated geometry and
//!   fixed costs, and a candidate the loop refuses (a pixel that does not fit alone, more than
//!   [`oit_core::tiling::MAX_TILES`] windows) is refused. On a hardware raster path the GPU
//!   rasterizes each window itself, so fragments at the seams may differ from the whole frame's
//!   (the CPU and compute paths give the same fragments bit for bit): there a tiled candidate has
//!   no bound below 1.
//! - its **predicted time** from the backend/path's calibration ([`crate::model::TechniqueModel::predict`])
//!   with the geometry passes its plan runs at this N ([`geometry_passes`]).
//!
//! Besides the catalogue's techniques as calibrated, the count itself opens two exact
//! candidates: `fabs:N` and `mdts64:N` (N the counted deepest pixel) need no counting pass of
//! their own, one geometry pass fewer than `fabs` and `mdts64` (predicted with those techniques'
//! models at one pass); and, under a non-zero `--max-epr`, `fabs:K` with the smallest K whose
//! bound meets it. The pick is the cheapest predicted candidate within both budgets
//! ([`choose`]); [`Choice`] keeps every candidate with its prediction, bound, storage and, for
//! the refused, the reason.
//!
//! The cost table per backend/path ([`Tables`]): a calibration file given (`--calibration`,
//! written by `oit bench --calibrate`) first, then the CPU calibration shipped with oit-bench
//! ([`crate::model::CPU_CALIBRATION`]) and the committed H200 calibration ([`H200_CALIBRATION`],
//! both wgpu raster paths). A backend/path none of them has is ranked with the closest table
//! there is (vulkan's compute path by wgpu's compute path, which runs the same WGSL kernels; else
//! the CPU's), and the choice says so: the ranking then rests on another device's relative costs.

use oit_core::plan::{Counted, Plan, Sizing};
use oit_core::tiling::{Forecast, Rect};
use oit_core::{Backend, Camera, OitError, RasterPath, Scene, Settings, Technique};
use serde::Serialize;

use crate::model::{CPU_CALIBRATION, Calibration, ModelFile, SceneStats, geometry_passes};

/// The committed calibration of the H200 (both wgpu raster paths, 1024²): the cost table of the
/// wgpu backend when no `--calibration` file is given.
///
/// The crate's copy (`data/h200-calibration.json`) of the repository's
/// `bench/results/h200/calibration.json`, so that the packaged crate holds it; a test of the
/// workspace (`tests/tests/packaging.rs`) checks that the two are the same bytes.
pub const H200_CALIBRATION: &str = include_str!("../data/h200-calibration.json");

/// The budgets a choice must meet.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Budget {
    /// Largest error pixel rate allowed, a fraction in [0, 1]; 0 asks for an exact technique.
    pub max_epr: f64,
    /// Largest storage of a frame (or of each of its screen tiles), bytes; `None`: the device's.
    pub memory: Option<u64>,
}

impl Budget {
    /// A budget, checked: `max_epr` finite and in [0, 1], `memory` at least one byte.
    pub fn new(max_epr: f64, memory: Option<u64>) -> Result<Budget, OitError> {
        if !(max_epr.is_finite() && (0.0..=1.0).contains(&max_epr)) {
            return Err(OitError::InvalidSettings(format!(
                "--max-epr {max_epr} is not an error pixel rate: use a fraction from 0 to 1 (0.001) or a \
                 percentage (0.1%)"
            )));
        }
        if memory == Some(0) {
            return Err(OitError::InvalidSettings(
                "--memory must be at least 1 byte, e.g. --memory 512M".into(),
            ));
        }
        Ok(Budget { max_epr, memory })
    }
}

/// Parses `--max-epr`: a fraction (`0.001`) or a percentage (`0.1%`), from 0 to 1 (100 %).
pub fn parse_max_epr(text: &str) -> Result<f64, OitError> {
    let t = text.trim();
    let (number, scale) = match t.strip_suffix('%') {
        Some(n) => (n.trim(), 0.01),
        None => (t, 1.0),
    };
    let value = number.parse::<f64>().ok().filter(|v| v.is_finite()).map(|v| v * scale).ok_or_else(|| {
        OitError::InvalidSettings(format!(
            "--max-epr '{text}' is not a number: use a fraction from 0 to 1 (0.001) or a percentage (0.1%)"
        ))
    })?;
    Budget::new(value, None).map(|b| b.max_epr)
}

/// The cost tables `auto` ranks by, in the order they are consulted.
#[derive(Clone, Debug)]
pub struct Tables {
    files: Vec<(ModelFile, String)>,
}

impl Tables {
    /// The shipped tables (CPU, H200), after `given` (a file and its name) where there is one.
    pub fn new(given: Option<(ModelFile, String)>) -> Result<Tables, OitError> {
        let mut files: Vec<(ModelFile, String)> = given.into_iter().collect();
        files.push((
            ModelFile::parse(CPU_CALIBRATION, "the shipped CPU calibration")?,
            "bench/results/cpu/calibration.json (shipped)".into(),
        ));
        files.push((
            ModelFile::parse(H200_CALIBRATION, "the shipped H200 calibration")?,
            "bench/results/h200/calibration.json (shipped)".into(),
        ));
        Ok(Tables { files })
    }

    /// The calibration for backend/path `label` (`cpu`, `wgpu/hardware`, `vulkan/compute`, ...),
    /// and where it came from, in words, saying when it is a stand-in for another device's.
    pub fn lookup(&self, label: &str) -> Option<(&Calibration, String)> {
        for (file, name) in &self.files {
            if let Some(c) = file.backend(label) {
                return Some((c, format!("{label} table of {name}, {}", c.device)));
            }
        }
        // the same WGSL compute kernels on another API: wgpu's compute path is the closest
        let path = label.split_once('/').map(|(_, p)| p);
        if path == Some("compute") {
            for (file, name) in &self.files {
                if let Some(c) = file.backend("wgpu/compute") {
                    return Some((
                        c,
                        format!(
                            "no calibration for {label}: ranked by the wgpu/compute table of {name} ({}), \
                             the same WGSL kernels; predicted times are that device's",
                            c.device
                        ),
                    ));
                }
            }
        }
        for (file, name) in &self.files {
            if let Some(c) = file.backend("cpu") {
                return Some((
                    c,
                    format!(
                        "no calibration for {label}: ranked by the CPU table of {name} ({}); predicted \
                         times are the CPU's, only their order is used (run `oit bench --calibrate` on \
                         this device and pass --calibration)",
                        c.device
                    ),
                ));
            }
        }
        None
    }
}

/// One technique `auto` considered.
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    /// The technique, parameters included.
    pub technique: String,
    /// The backend/path it would run on.
    pub backend: String,
    /// The calibrated technique whose model predicts it (`fabs` for `fabs:12`), if any.
    pub model: Option<String>,
    /// Geometry passes its plan runs at the counted deepest pixel (per tile).
    pub passes: u32,
    /// Predicted milliseconds, screen tiles included; `None` where no model predicts it.
    pub predicted_ms: Option<f64>,
    /// Upper bound of its error pixel rate on this scene ([`epr_bound`]).
    pub epr_bound: f64,
    /// Why the bound is what it is.
    pub epr_reason: String,
    /// Storage the frame will report, bytes: its largest screen tile's (the whole frame's when it
    /// runs in one), the technique's arrays as [`oit_core::Stats::storage_bytes`] counts them
    /// ([`oit_core::tiling::Forecast::storage_bytes`]).
    pub storage_bytes: u64,
    /// The largest tile's bytes held to `--memory` (or the host's budget): its storage, resolve
    /// state, outputs and the backend's extra ([`oit_core::tiling::Forecast::frame_bytes`]).
    pub frame_bytes: u64,
    /// Screen tiles it will run in (1 when it fits): [`oit_core::Stats::tiles`] of its frame; 0
    /// where the tiling loop refuses it (then `rejected` says why).
    pub tiles: u64,
    /// Why it was not eligible; `None` for a candidate within both budgets.
    pub rejected: Option<String>,
}

/// What `auto` picked, and why.
#[derive(Clone, Debug, Serialize)]
pub struct Choice {
    /// The technique picked.
    pub technique: Technique,
    /// The budgets.
    pub budget: Budget,
    /// The counting pass's deepest pixel: N.
    pub deepest: u32,
    /// Pixels with at least one fragment.
    pub covered_pixels: u64,
    /// Fragments of the frame.
    pub fragments: u64,
    /// The cost table of the pick's backend/path, in words.
    pub calibration: String,
    /// The pick's reason, in words.
    pub reason: String,
    /// Every candidate, cheapest predicted first (eligible ones before refused ones).
    pub candidates: Vec<Candidate>,
}

impl Choice {
    /// The picked candidate.
    pub fn picked(&self) -> &Candidate {
        &self.candidates[0]
    }
}

/// The counting pass: the reference frame's per-pixel fragment counts on `backend` at `camera` and
/// `settings` (its technique replaced by the reference), as the model's statistics, with the
/// counting frame (its layers included) for a caller that reports depth complexity. The count is
/// `auto`'s own work, not the frame the budget is for: it runs without `--memory` (the device's
/// limits still tile it where they must).
pub fn count(
    backend: &dyn Backend,
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
) -> Result<(SceneStats, oit_core::Frame), OitError> {
    let reference = Settings { technique: Technique::Reference, memory: None, ..settings.clone() };
    let frame = backend.render(scene, camera, &reference)?;
    let layers = frame.layers.as_ref().ok_or_else(|| {
        OitError::Device(format!(
            "{}'s reference frame came back without its per-pixel counts",
            backend.name()
        ))
    })?;
    let stats = SceneStats::from_layers(scene.triangle_count(), frame.stats.fragments, layers);
    Ok((stats, frame))
}

/// Pixels of `stats` with at least one fragment.
fn covered(stats: &SceneStats) -> u64 {
    stats.histogram.iter().skip(1).sum()
}

/// The share of covered pixels holding more than `layers` fragments (0 with nothing covered).
pub fn share_deeper(stats: &SceneStats, layers: u32) -> f64 {
    let covered = covered(stats);
    if covered == 0 {
        return 0.0;
    }
    let deeper: u64 = stats.histogram.iter().skip(layers as usize + 1).sum();
    deeper as f64 / covered as f64
}

/// An upper bound on the error pixel rate of `plan`'s technique on a scene of `stats`, and why
/// (see the module docs): the share of covered pixels where it can differ from the reference.
pub fn epr_bound(plan: &Plan, stats: &SceneStats) -> (f64, String) {
    let n = stats.deepest();
    let fixed = match plan.sizing {
        Sizing::Fixed(k) => Some(k),
        _ => None,
    };
    let two = share_deeper(stats, 1);
    match plan.technique {
        Technique::Reference | Technique::Dfb | Technique::Ll => {
            (0.0, "exact: every fragment kept, sorted by (depth, primitive id) as the reference".into())
        }
        // kbuf keeps the same K nearest by (depth, primitive id) as fabs:K
        Technique::Fabs { .. } | Technique::Kbuf { .. } => match fixed {
            Some(k) if k < n => (
                share_deeper(stats, k),
                format!(
                    "pixels deeper than K = {k} keep their {k} nearest and lose the rest; the others are exact"
                ),
            ),
            _ => (0.0, "exact: K at least the deepest pixel, sorted by (depth, primitive id)".into()),
        },
        Technique::Dp | Technique::Ddp | Technique::Mlp { .. } | Technique::Mdts64 { .. } => (
            two,
            format!(
                "exact but for equal depths, ordered by payload, not primitive id{}: only pixels of 2 or \
                 more fragments can differ",
                if fixed.is_some_and(|k| k < n) { ", and layers past K lost" } else { "" }
            ),
        ),
        Technique::Plain => (two, ORDER_IGNORED.into()),
        // the colour mode keeps alpha in 7 bits (counted as `quantized`): a pixel of one fragment
        // can differ too
        Technique::Bdp { .. } if plan.bdp_color => (
            if covered(stats) > 0 { 1.0 } else { 0.0 },
            "alpha kept in 7 bits and bucket collisions: any covered pixel can differ (by at most n/255 of \
             linear colour at a pixel of n layers where nothing collided)"
                .into(),
        ),
        Technique::Bdp { .. } => (
            two,
            "bucket collisions need 2 fragments in one bucket: only pixels of 2 or more can differ".into(),
        ),
        Technique::Adp => {
            (two, "fragments sharing one of 1024 bins are lost: only pixels of 2 or more can differ".into())
        }
        Technique::Mdts { .. } => (
            if covered(stats) > 0 { 1.0 } else { 0.0 },
            "no bound: one 8-bit alpha for every fragment and depths equal at 2⁻²⁰; any covered pixel \
             can differ"
                .into(),
        ),
        // the order-free sums (`Technique::sums`): exact at a pixel of one fragment, as plain;
        // a technique with no arm here and no sums gets no bound (any covered pixel can differ)
        t if t.sums().is_some() => (two, ORDER_IGNORED.into()),
        t => (
            if covered(stats) > 0 { 1.0 } else { 0.0 },
            format!("no bound known for {t}: any covered pixel can differ"),
        ),
    }
}

/// Why a technique that ignores order (plain, and the order-free sums) is bounded by the share of
/// pixels of two fragments or more.
const ORDER_IGNORED: &str = "order ignored: exact at one fragment, any pixel of 2 or more can differ";

/// The calibrated technique whose model predicts `technique`: itself, or its family sized from the
/// count (`fabs:K` → `fabs`, `mdts64:K` → `mdts64`); `None` for parameters never calibrated.
fn model_name(technique: Technique, calibration: &Calibration) -> Option<String> {
    let own = technique.to_string();
    if calibration.technique(&own).is_some() {
        return Some(own);
    }
    let family = match technique {
        Technique::Fabs { k: Some(_) } => Technique::Fabs { k: None },
        Technique::Mdts { k: Some(_) } => Technique::Mdts { k: None },
        Technique::Mdts64 { k: Some(_) } => Technique::Mdts64 { k: None },
        _ => return None,
    };
    calibration.technique(&family.to_string()).map(|_| family.to_string())
}

/// The techniques `auto` considers on a scene whose deepest pixel holds `n` fragments, under
/// `max_epr`: the catalogue's (reference excluded), `fabs:N` and `mdts64:N`, and the smallest
/// `fabs:K` whose bound meets `max_epr` where it is below N.
pub fn candidates(stats: &SceneStats, max_epr: f64) -> Vec<Technique> {
    let n = stats.deepest().clamp(1, oit_core::MAX_PARAMETER);
    let mut out = Technique::all();
    out.push(Technique::Fabs { k: Some(n) });
    out.push(Technique::Mdts64 { k: Some(n) });
    if let Some(k) = (1..n).find(|&k| share_deeper(stats, k) <= max_epr) {
        out.push(Technique::Fabs { k: Some(k) });
    }
    out
}

/// What the counting frame's per-pixel counts `layers` (rows of `settings`' frame) hold in the
/// window `rect` (in the full frame's pixels): its deepest pixel and its fragments, what the
/// window's own counting pass finds.
fn counted_in(layers: &[u32], settings: &Settings, rect: Rect) -> Counted {
    let (x0, y0) = settings.region.map_or((0, 0), |r| (r.x, r.y));
    let width = settings.width as usize;
    let mut out = Counted::default();
    for y in rect.y..rect.y + rect.height {
        let start = (y - y0) as usize * width + (rect.x - x0) as usize;
        for &n in layers.get(start..start + rect.width as usize).unwrap_or_default() {
            out.deepest = out.deepest.max(n);
            out.fragments += u64::from(n);
        }
    }
    out
}

/// Chooses for `backend` (its raster path per technique as `settings` gives it) on `scene`, whose
/// counting pass gave `stats` and the per-pixel counts `layers` (the reference's
/// `Frame::layers`): every [`candidates`] entry judged against `budget` and ranked by predicted
/// time from `tables`; a clear error when none is within the budgets. Its tiles and storage are
/// those of the frame of `settings` under `budget.memory`.
pub fn choose(
    backend: &dyn Backend,
    scene: &Scene,
    settings: &Settings,
    (stats, layers): (&SceneStats, &[u32]),
    tables: &Tables,
    budget: Budget,
) -> Result<Choice, OitError> {
    let n = stats.deepest();
    let pixels = stats.pixels;
    let supported = backend.capabilities().techniques;
    let mut judged: Vec<(Candidate, String)> = Vec::new();
    for technique in candidates(stats, budget.max_epr) {
        let s = Settings { technique, memory: budget.memory, ..settings.clone() };
        let label = crate::label(backend, &s);
        let name = technique.to_string();
        let refused = |reason: String| Candidate {
            technique: name.clone(),
            backend: label.clone(),
            model: None,
            passes: 0,
            predicted_ms: None,
            epr_bound: f64::NAN,
            epr_reason: String::new(),
            storage_bytes: 0,
            frame_bytes: 0,
            tiles: 0,
            rejected: Some(reason),
        };
        if !supported.contains(&technique.kind()) {
            judged.push((refused(format!("{} does not run it", backend.name())), String::new()));
            continue;
        }
        let plan = match Plan::new(backend.name(), scene, &s) {
            Ok(p) => p.on_path(backend.raster_path(&s)),
            Err(e) => {
                judged.push((refused(e.to_string()), String::new()));
                continue;
            }
        };
        let (mut epr, mut epr_reason) = epr_bound(&plan, stats);
        let passes = geometry_passes(&plan, n);
        let table = tables.lookup(&label);
        let model = table.as_ref().and_then(|(c, _)| model_name(technique, c));
        let mut rejected = Vec::new();
        // the frame's own tiling loop, run on the count: the tiles and storage it will have
        let forecast = oit_core::tiling::forecast(
            backend.name(),
            scene,
            &s,
            backend.raster_path(&s),
            backend.frame_extra_bytes(&s),
            |rect| counted_in(layers, settings, rect),
        )
        .unwrap_or_else(|e| {
            rejected.push(e.to_string());
            Forecast::default()
        });
        // 0 where the loop refuses the frame
        let tiles = u64::from(forecast.tiles);
        let mut seams = false;
        if tiles > 1 && backend.raster_path(&s) == RasterPath::Hardware && covered(stats) > 0 {
            seams = epr < 1.0;
            epr = 1.0;
            epr_reason = format!(
                "{epr_reason}; but in screen tiles on the hardware raster path, where the GPU \
                 rasterizes each window itself and fragments at the seams may differ from the \
                 whole frame's: no bound"
            );
        }
        if epr > budget.max_epr {
            rejected.push(format!(
                "EPR bound {epr:.4} over --max-epr {}{}",
                budget.max_epr,
                if seams { " (in screen tiles on the hardware raster path)" } else { "" }
            ));
        }
        let predicted = match (&table, &model) {
            (Some((c, _)), Some(m)) => c.technique(m).map(|t| {
                let once = t.predict(passes, stats);
                // each further tile sets the whole scene up again: its triangles and fixed cost
                let repeated =
                    t.coefficients[0] * f64::from(passes) * stats.triangles as f64 * 1e-6 + t.coefficients[4];
                once + tiles.saturating_sub(1) as f64 * repeated
            }),
            _ => None,
        };
        if predicted.is_none() {
            rejected.push(format!("no model for it in the {label} cost table"));
        }
        let source = table.map(|(_, s)| s).unwrap_or_default();
        judged.push((
            Candidate {
                technique: name,
                backend: label,
                model,
                passes,
                predicted_ms: predicted,
                epr_bound: epr,
                epr_reason,
                storage_bytes: forecast.storage_bytes,
                frame_bytes: forecast.frame_bytes,
                tiles,
                rejected: (!rejected.is_empty()).then(|| rejected.join("; ")),
            },
            source,
        ));
    }
    // eligible first, then by predicted time (unpredicted last), then by name for a stable order
    judged.sort_by(|(a, _), (b, _)| {
        a.rejected
            .is_some()
            .cmp(&b.rejected.is_some())
            .then(a.predicted_ms.unwrap_or(f64::INFINITY).total_cmp(&b.predicted_ms.unwrap_or(f64::INFINITY)))
            .then(a.technique.cmp(&b.technique))
    });
    let eligible = judged.iter().filter(|(c, _)| c.rejected.is_none()).count();
    let Some((first, calibration)) = judged.first().filter(|(c, _)| c.rejected.is_none()).cloned() else {
        let exact: Vec<String> = judged
            .iter()
            .filter(|(c, _)| c.epr_reason.starts_with("exact:"))
            .map(|(c, _)| format!("{} ({})", c.technique, c.rejected.as_deref().unwrap_or("eligible")))
            .collect();
        return Err(OitError::InvalidSettings(format!(
            "auto: no technique on {} meets --max-epr {}{} for this scene ({} pixels, deepest {n}, {} \
             fragments); the exact ones: {}",
            backend.name(),
            budget.max_epr,
            budget.memory.map(|m| format!(" and --memory {m}")).unwrap_or_default(),
            pixels,
            stats.fragments,
            if exact.is_empty() { "none".into() } else { exact.join(", ") }
        )));
    };
    let technique: Technique = first.technique.parse()?;
    let next = judged
        .get(1)
        .filter(|(c, _)| c.rejected.is_none())
        .map(|(c, _)| format!("; next {} at {:.2} ms", c.technique, c.predicted_ms.unwrap_or(f64::NAN)))
        .unwrap_or_default();
    let reason = format!(
        "{}: the cheapest predicted ({:.2} ms, {} geometry pass{}{}) of {eligible} candidate{} within \
         --max-epr {}{} (EPR bound {:.4}: {}){next}",
        first.technique,
        first.predicted_ms.unwrap_or(f64::NAN),
        first.passes,
        if first.passes == 1 { "" } else { "es" },
        if first.tiles > 1 {
            format!(", {} screen tiles, {} bytes of storage in the largest", first.tiles, first.storage_bytes)
        } else {
            format!(", {} bytes of storage", first.storage_bytes)
        },
        if eligible == 1 { "" } else { "s" },
        budget.max_epr,
        budget.memory.map(|m| format!(" and --memory {m}")).unwrap_or_default(),
        first.epr_bound,
        first.epr_reason,
    );
    Ok(Choice {
        technique,
        budget,
        deepest: n,
        covered_pixels: covered(stats),
        fragments: stats.fragments,
        calibration,
        reason,
        candidates: judged.into_iter().map(|(c, _)| c).collect(),
    })
}

/// The counting pass, then the choice: what `oit render --technique auto` runs before it renders.
/// Returns the choice and the counting frame (the reference, its per-pixel counts included).
pub fn resolve(
    backend: &dyn Backend,
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    tables: &Tables,
    budget: Budget,
) -> Result<(Choice, oit_core::Frame), OitError> {
    let (stats, frame) = count(backend, scene, camera, settings)?;
    let layers = frame.layers.as_deref().unwrap_or_default();
    Ok((choose(backend, scene, settings, (&stats, layers), tables, budget)?, frame))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(t: &str) -> Plan {
        let s = Settings { technique: t.parse().unwrap(), ..Default::default() };
        Plan::new("test", &oit_core::load_scene("planes:2").unwrap(), &s).unwrap()
    }

    /// 10 pixels: 2 empty, 3 of one fragment, 3 of two, 1 of four, 1 of nine.
    fn stats() -> SceneStats {
        SceneStats::from_layers(100, 3 + 6 + 4 + 9, &[0, 0, 1, 1, 1, 2, 2, 2, 4, 9])
    }

    #[test]
    fn bounds_follow_the_histogram() {
        let s = stats();
        assert_eq!(share_deeper(&s, 0), 1.0);
        assert_eq!(share_deeper(&s, 1), 5.0 / 8.0);
        assert_eq!(share_deeper(&s, 3), 2.0 / 8.0);
        assert_eq!(share_deeper(&s, 9), 0.0);
        for exact in ["dfb", "ll", "fabs", "fabs:9", "fabs:12"] {
            assert_eq!(epr_bound(&plan(exact), &s).0, 0.0, "{exact}");
        }
        assert_eq!(epr_bound(&plan("fabs:3"), &s).0, 2.0 / 8.0);
        assert_eq!(epr_bound(&plan("fabs:1"), &s).0, 5.0 / 8.0);
        for two in ["dp", "ddp", "mlp:4", "mdts64", "mdts64:2", "wavg", "wsum", "bdp2", "adp"] {
            assert_eq!(epr_bound(&plan(two), &s).0, 5.0 / 8.0, "{two}");
        }
        assert_eq!(epr_bound(&plan("mdts"), &s).0, 1.0);
        // bdp's colour mode: a pixel of one fragment differs by its 7-bit alpha too
        assert!(plan("bdp").bdp_color);
        assert_eq!(epr_bound(&plan("bdp"), &s).0, 1.0);
        // nothing covered: nothing can be wrong
        let empty = SceneStats::from_layers(1, 0, &[0, 0]);
        assert_eq!(epr_bound(&plan("mdts"), &empty).0, 0.0);
        assert_eq!(epr_bound(&plan("fabs:1"), &empty).0, 0.0);
    }

    #[test]
    fn candidates_add_the_counted_sizes() {
        let s = stats();
        let names: Vec<String> = candidates(&s, 0.0).iter().map(ToString::to_string).collect();
        assert!(names.contains(&"fabs:9".into()) && names.contains(&"mdts64:9".into()), "{names:?}");
        assert!(!names.iter().any(|n| n.starts_with("fabs:") && n != "fabs:9"), "{names:?}");
        // 0.25 admits fabs:2 (two pixels of eight deeper than 2), 0.2 only fabs:4 (one)
        let names: Vec<String> = candidates(&s, 0.25).iter().map(ToString::to_string).collect();
        assert!(names.contains(&"fabs:2".into()) && !names.contains(&"fabs:1".into()), "{names:?}");
        let names: Vec<String> = candidates(&s, 0.2).iter().map(ToString::to_string).collect();
        assert!(names.contains(&"fabs:4".into()) && !names.contains(&"fabs:3".into()), "{names:?}");
    }

    #[test]
    fn budgets_are_checked() {
        assert_eq!(parse_max_epr("0.001").unwrap(), 0.001);
        assert!((parse_max_epr("0.1%").unwrap() - 0.001).abs() < 1e-15);
        assert_eq!(parse_max_epr(" 0 ").unwrap(), 0.0);
        for bad in ["-0.1", "1.5", "101%", "nan", "inf", "x", ""] {
            let e = parse_max_epr(bad).unwrap_err().to_string();
            assert!(e.contains("--max-epr"), "{bad}: {e}");
        }
        assert!(Budget::new(0.0, Some(0)).is_err());
    }

    #[test]
    fn tables_fall_back_and_say_so() {
        let tables = Tables::new(None).unwrap();
        let (c, note) = tables.lookup("cpu").unwrap();
        assert_eq!(c.backend, "cpu");
        assert!(!note.contains("no calibration"), "{note}");
        let (c, note) = tables.lookup("wgpu/hardware").unwrap();
        assert_eq!(c.backend, "wgpu/hardware");
        assert!(note.contains("H200"), "{note}");
        let (c, note) = tables.lookup("vulkan/compute").unwrap();
        assert_eq!(c.backend, "wgpu/compute");
        assert!(note.contains("no calibration for vulkan/compute"), "{note}");
        let (c, note) = tables.lookup("elsewhere/hardware").unwrap();
        assert_eq!(c.backend, "cpu");
        assert!(note.contains("ranked by the CPU table"), "{note}");
    }

    #[test]
    fn family_models_stand_in_for_counted_sizes() {
        let tables = Tables::new(None).unwrap();
        let (cpu, _) = tables.lookup("cpu").unwrap();
        assert_eq!(model_name(Technique::Fabs { k: Some(7) }, cpu).as_deref(), Some("fabs"));
        assert_eq!(model_name(Technique::Mdts64 { k: Some(7) }, cpu).as_deref(), Some("mdts64"));
        assert_eq!(model_name(Technique::Mlp { m: 4 }, cpu).as_deref(), Some("mlp:4"));
        assert_eq!(model_name(Technique::Mlp { m: 3 }, cpu), None);
        assert_eq!(model_name(Technique::Bdp { passes: 5 }, cpu), None);
        // a technique has a model exactly where the table calibrated it (the shipped CPU table
        // has plain since its recalibration)
        assert_eq!(model_name(Technique::Plain, cpu).is_some(), cpu.technique("plain").is_some());
    }
}
