//! Screen tiles: a frame whose storage does not fit its memory budget runs as windows of the
//! screen that each fit, one after another, and the windows' images, per-pixel outputs and
//! counters are put back together. One loop for every backend and technique: each backend's
//! [`crate::Prepared::frame`] runs its frame through [`run`].
//!
//! A window is a frame of its own size with [`Settings::region`] saying where it lies in the full
//! frame. Setup snaps in the full frame's viewport and shifts by the window's origin, so on the
//! CPU and compute-raster paths a window's fragments are the full frame's there, bit for bit, and
//! since every technique decides per pixel (what it keeps, loses and how it composites), the
//! stitched frame equals the untiled one: image, `lost_pixels`, `layers` and the counters
//! `fragments`, `captured`, `lost`, `tied` and `max_layers`. What tiling changes is counted:
//! `geometry_passes` adds up every window's passes (the extra passes tiling costs),
//! `storage_bytes` is the largest window's (windows run one at a time and each fits the budget)
//! and [`crate::Stats::tiles`] says how many windows ran.
//!
//! When the frame splits:
//! - before anything runs, when `--memory` is set and the plan's frame (its storage and outputs,
//!   [`Plan::frame_bytes`], before any counting pass) is over it: into the fewest near-square
//!   tiles of a grid that each fit ([`grid`]) beside what the whole frame keeps while its tiles
//!   run, the stitched image and per-pixel outputs ([`Plan::stitched_bytes`]; each window is
//!   placed as it finishes and dropped). Each window runs under `--memory` less that, so a
//!   backend's own checks (sizes found by a counting pass) hold it to the same total; a budget
//!   that cannot hold the stitched outputs beside a one-pixel tile is a clear error;
//! - when a backend refuses a window as too large ([`OitError::TooLarge`]: over the budget, over a
//!   device limit such as a storage binding's size, or, for techniques sized by a counting pass,
//!   found over after that pass): that window splits into as many tiles as the refusal's
//!   needed/limit ratio says, with a margin ([`split`]; in four where the refusal gives no ratio),
//!   and each runs again, recursively, down to a single pixel; a pixel that does not fit alone is
//!   a clear error, and so is a frame that would need more than [`MAX_TILES`] windows (without
//!   `--memory`, more than [`AUTO_TILES`]: the device's refusal stands).
//!
//! Both decisions are one loop (`windows`), run by the frame ([`run_with`]) and, before any
//! frame, by [`forecast`], which refuses a window where its [`Plan::frame_bytes`] with its part
//! of a counting pass is over its budget, as oit-cpu does (a window sized by a count is checked
//! whole once the count is known, so its refusal gives the true ratio): `auto` reports the tiles
//! and storage the frame then has.

use std::collections::VecDeque;
use std::time::Instant;

use crate::plan::{Counted, Plan};
use crate::{Frame, Image, OitError, Region, Scene, Settings, Stats};

/// The most windows one frame runs in: each window sets up the whole scene again, so a budget
/// that needs more is refused with a clear error rather than left to run for hours.
pub const MAX_TILES: usize = 4096;

/// The most windows a frame runs in when no `--memory` is set and the device refuses it as too
/// large: beyond this the device's own refusal is the answer (a frame that far over the device
/// asks for a smaller size or technique, not hours of tiles). 1024 lets a 16384² frame of a mesh
/// run on lavapipe, whose storage bindings hold 128 MiB (the armadillo's `fabs` there needs about
/// 250 windows), and still refuses `fabs:65536` at 512² (over a thousand).
pub const AUTO_TILES: usize = 1024;

/// Without `--memory`, a frame whose refused storage is more than this many times the host's
/// budget ([`crate::plan::host_memory_budget`]) is refused, not tiled (lavapipe's 16384²
/// armadillo `fabs`, tiled for its 128 MiB bindings, needs about 3 times; `bdp:65536` at 512²
/// on the CPU about 200).
pub const AUTO_WORK: u64 = 16;

/// The windows a window refused as too large runs as instead: a grid whose tiles each hold at
/// most 85 % of the refused window's pixels divided by the refusal's needed/limit ratio (storage
/// grows with pixels; a tile's deepest pixel is no deeper than the window's; the margin covers
/// what does not shrink with the pixels), so one refusal costs one retry, not a cascade of
/// quarterings each with its own counting pass. In four when the refusal gives no ratio or the
/// grid would be one tile.
pub fn split(rect: Rect, refusal: &OitError) -> Vec<Rect> {
    if let OitError::TooLarge { needed, limit, .. } = *refusal
        && limit > 0
        && needed > limit
    {
        let ratio = needed as f64 / limit as f64;
        let most = ((rect.pixels() as f64 / ratio) * 0.85).floor().max(1.0) as u64;
        if let Some(tiles) = grid(rect, |pixels| pixels <= most)
            && tiles.len() > 1
        {
            return tiles;
        }
    }
    rect.quarters()
}

/// A window of the screen, in pixels of the full frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

impl Rect {
    /// Pixels in the window.
    pub fn pixels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// The window's four quarters (two halves where it is one pixel wide or high; empty parts
    /// left out).
    pub fn quarters(&self) -> Vec<Rect> {
        let (w0, h0) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let mut out = Vec::with_capacity(4);
        for (y, h) in [(self.y, h0), (self.y + h0, self.height - h0)] {
            for (x, w) in [(self.x, w0), (self.x + w0, self.width - w0)] {
                if w > 0 && h > 0 {
                    out.push(Rect { x, y, width: w, height: h });
                }
            }
        }
        out
    }
}

/// The fewest tiles of a `cols × rows` grid over `area` whose largest tile `fits` (a test on its
/// pixel count), near-square: the grid grows a column where tiles are wider than high, else a
/// row. Tiles are `⌈width / cols⌉ × ⌈height / rows⌉`, the last column and row what is left (an
/// uneven tiling). `None` when even one-pixel tiles do not fit, or more than [`MAX_TILES`] are
/// needed.
pub fn grid(area: Rect, fits: impl Fn(u64) -> bool) -> Option<Vec<Rect>> {
    let (mut cols, mut rows) = (1u32, 1u32);
    loop {
        let (tw, th) = (area.width.div_ceil(cols), area.height.div_ceil(rows));
        if fits(u64::from(tw) * u64::from(th)) {
            break;
        }
        let grow_cols = (tw >= th && cols < area.width) || rows >= area.height;
        if grow_cols && cols < area.width {
            cols += 1;
        } else if rows < area.height {
            rows += 1;
        } else {
            return None;
        }
        if u64::from(cols) * u64::from(rows) > 4 * MAX_TILES as u64 {
            return None;
        }
    }
    let (tw, th) = (area.width.div_ceil(cols), area.height.div_ceil(rows));
    let mut tiles = Vec::new();
    for y in (0..area.height).step_by(th as usize) {
        for x in (0..area.width).step_by(tw as usize) {
            tiles.push(Rect {
                x: area.x + x,
                y: area.y + y,
                width: tw.min(area.width - x),
                height: th.min(area.height - y),
            });
        }
    }
    (tiles.len() <= MAX_TILES).then_some(tiles)
}

/// The settings of the window `rect` of the frame `full` (width, height): its own size and its
/// region (none where the window is the whole frame, so an untiled frame runs as before).
pub fn window(settings: &Settings, full: (u32, u32), rect: Rect) -> Settings {
    let whole = rect == Rect { x: 0, y: 0, width: full.0, height: full.1 };
    Settings {
        width: rect.width,
        height: rect.height,
        region: (!whole).then_some(Region { x: rect.x, y: rect.y, full_width: full.0, full_height: full.1 }),
        ..settings.clone()
    }
}

/// A GPU backend's `Prepared::frame_stats`: the frame untiled without its image read back
/// (`untiled`), unless it must run in tiles (`--memory` set, or the untiled frame refused as too
/// large), which `tiled` (the backend's `Prepared::frame`, image and all) runs.
pub fn frame_stats<P: ?Sized>(
    settings: &Settings,
    prepared: &mut P,
    untiled: impl FnOnce(&mut P) -> Result<Frame, OitError>,
    tiled: impl FnOnce(&mut P) -> Result<Frame, OitError>,
) -> Result<Stats, OitError> {
    let stats = |f: Frame| {
        let mut s = f.stats;
        s.count_packing(settings);
        s
    };
    if settings.memory.is_none() {
        match untiled(prepared) {
            Err(OitError::TooLarge { .. }) => {}
            other => return other.map(stats),
        }
    }
    tiled(prepared).map(stats)
}

/// Runs one frame of `settings` through `frame` (a backend's untiled frame), in as many windows
/// as its memory budget and the backend's refusals need (module docs), and puts them together.
/// `backend` names the backend, for messages; `scene` is what the plan sizes storage from.
pub fn run(
    backend: &str,
    scene: &Scene,
    settings: &Settings,
    frame: impl FnMut(&Settings) -> Result<Frame, OitError>,
) -> Result<Frame, OitError> {
    run_with(backend, scene, settings, 0, frame)
}

/// [`run`] for a backend whose frame holds `extra` bytes a pixel beyond the plan's
/// [`Plan::frame_bytes`] (oit-cpu's resolve states, larger than the plan's 23 words): tiles are
/// sized by both.
pub fn run_with(
    backend: &str,
    scene: &Scene,
    settings: &Settings,
    extra: u64,
    mut frame: impl FnMut(&Settings) -> Result<Frame, OitError>,
) -> Result<Frame, OitError> {
    let start = Instant::now();
    let (root, _) = root(settings);
    let mut stitched: Option<Stitched> = None;
    let tiles = windows(
        backend,
        scene,
        settings,
        extra,
        |_, s| frame(s),
        |rect, f| {
            if rect == root {
                // the frame ran whole: nothing to stitch
                stitched = Some(Stitched::whole(f));
                Ok(())
            } else {
                stitched.get_or_insert_with(|| Stitched::new(root, &f)).place(root, rect, f)
            }
        },
    )?;
    let Some(stitched) = stitched else {
        return Err(OitError::Device(format!(
            "a frame of {}x{} ran in no screen tile",
            root.width, root.height
        )));
    };
    let mut frame = stitched.finish();
    frame.stats.tiles = tiles.max(1) as u32;
    frame.stats.count_packing(settings);
    if frame.stats.tiles > 1 {
        frame.stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    }
    Ok(frame)
}

/// The window a frame of `settings` covers in its full frame, and the full frame's size.
fn root(settings: &Settings) -> (Rect, (u32, u32)) {
    match settings.region {
        None => (
            Rect { x: 0, y: 0, width: settings.width, height: settings.height },
            (settings.width, settings.height),
        ),
        Some(r) => (
            Rect { x: r.x, y: r.y, width: settings.width, height: settings.height },
            (r.full_width, r.full_height),
        ),
    }
}

/// The one decision of which windows a frame of `settings` runs as (module docs), whether the
/// frame then runs ([`run_with`]) or is only foreseen ([`forecast`]): the first grid from the
/// plan and `--memory`, then each window through `frame` (its rectangle and settings), each one
/// done handed to `done`, each one refused as too large split and queued again. Returns the
/// windows that ran. One loop for both, so what `auto` predicts is what the frame does.
fn windows<T>(
    backend: &str,
    scene: &Scene,
    settings: &Settings,
    extra: u64,
    mut frame: impl FnMut(Rect, &Settings) -> Result<T, OitError>,
    mut done: impl FnMut(Rect, T) -> Result<(), OitError>,
) -> Result<usize, OitError> {
    settings.validate()?;
    let (root, full) = root(settings);
    // what a frame run in tiles keeps of the whole frame while its tiles run (the stitched
    // image and per-pixel outputs), and the budget its windows share: `--memory` less that
    let mut kept = None;
    let mut queue: VecDeque<Rect> = match settings.memory {
        None => VecDeque::from([root]),
        Some(budget) => {
            let plan = Plan::new(backend, scene, settings)?;
            let need = |pixels: u64| {
                plan.frame_bytes(pixels, Counted::default()).saturating_add(pixels.saturating_mul(extra))
            };
            if need(1) > budget {
                return Err(too_small(settings, need(1), budget));
            }
            let stitched = plan.stitched_bytes(root.pixels());
            if need(root.pixels()) > budget && stitched.saturating_add(need(1)) > budget {
                return Err(too_small_to_stitch(settings, root, stitched.saturating_add(need(1)), budget));
            }
            kept = Some(stitched);
            // the whole frame needs no stitching: it fits what a window fits plus what it keeps
            let fits = |pixels: u64| {
                let whole = pixels == root.pixels();
                need(pixels).saturating_add(if whole { 0 } else { stitched }) <= budget
            };
            grid(root, fits).ok_or_else(|| too_many(settings, need(root.pixels()), budget))?.into()
        }
    };
    // the windows' budget: what `--memory` leaves beside what the whole frame keeps (without
    // `--memory`, each backend's own budget)
    let window_settings = |rect: Rect| {
        let mut s = window(settings, full, rect);
        if rect != root
            && let (Some(memory), Some(kept)) = (settings.memory, kept)
        {
            s.memory = Some(memory.saturating_sub(kept).max(1));
        }
        s
    };
    let mut tiles = 0usize;
    while let Some(rect) = queue.pop_front() {
        match frame(rect, &window_settings(rect)) {
            Ok(f) => {
                tiles += 1;
                done(rect, f)?;
            }
            Err(e @ OitError::TooLarge { .. }) => {
                if rect.pixels() == 1 {
                    return Err(one_pixel_refused(e));
                }
                // without --memory, a refusal of more than AUTO_WORK times the host's budget is
                // not tiled at all: such a frame (bdp:65536, fabs:65536) asks for a smaller
                // technique or size, not hundreds of windows each filling the machine
                if settings.memory.is_none()
                    && let OitError::TooLarge { needed, .. } = e
                    && needed > AUTO_WORK.saturating_mul(crate::plan::host_memory_budget().1)
                {
                    return Err(e);
                }
                queue.extend(split(rect, &e));
                // without --memory, a device refusal tiles a frame only modestly: a request far
                // over the device (fabs:65536) is refused with the device's own error
                if settings.memory.is_none() && tiles + queue.len() > AUTO_TILES {
                    return Err(e);
                }
                if tiles + queue.len() > MAX_TILES {
                    return Err(OitError::TooLarge {
                        what: format!(
                            "{} at {}x{} in screen tiles",
                            settings.technique, root.width, root.height
                        ),
                        needed: (tiles + queue.len()) as u64,
                        limit_name: "oit's most tiles a frame (MAX_TILES)".into(),
                        limit: MAX_TILES as u64,
                        hint: format!("a window of {}x{} was still refused: {e}", rect.width, rect.height),
                    });
                }
            }
            Err(e) => return Err(e),
        }
    }
    Ok(tiles)
}

/// The budget a frame of `settings` (a whole frame, or a window of one) holds its storage and
/// outputs ([`Plan::frame_bytes`]) to on the host: half the host's available memory
/// ([`crate::plan::host_memory_budget`]), or `--memory` where smaller. A window of a frame in
/// screen tiles (`settings.region`) shares the host's half with what the whole frame keeps while
/// its tiles run ([`Plan::stitched_bytes`]); under `--memory` the tiling loop has taken that off
/// already. oit-cpu's budget, and what [`forecast`] foresees its refusals by.
pub fn host_budget(settings: &Settings, plan: &Plan) -> (String, u64) {
    let (name, mut bytes) = crate::plan::host_memory_budget();
    if let Some(r) = settings.region {
        let full = u64::from(r.full_width) * u64::from(r.full_height);
        bytes = bytes.saturating_sub(plan.stitched_bytes(full)).max(1);
    }
    settings.memory_budget((name.to_string(), bytes))
}

/// What a frame will run as, foreseen before it runs ([`forecast`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Forecast {
    /// Screen tiles it runs in (1 when it runs whole): [`crate::Stats::tiles`].
    pub tiles: u32,
    /// The largest window's storage, as the frame reports it ([`crate::Stats::storage_bytes`]:
    /// the technique's arrays, [`Plan::storage_bytes`] less the resolve state).
    pub storage_bytes: u64,
    /// The largest window's bytes held to its budget: [`Plan::frame_bytes`] and `extra`.
    pub frame_bytes: u64,
}

/// The windows a frame of `settings` on `path` runs as and the storage it reports, foreseen from
/// what a counting pass of the whole frame found, `counted` giving each window's part (its
/// deepest pixel and fragments). The loop is [`run_with`]'s own (`windows`); each window is
/// refused where the host's budget ([`host_budget`]) cannot hold its [`Plan::frame_bytes`] and
/// `extra` bytes a pixel, before its count and after it, as oit-cpu refuses it: exact for
/// oit-cpu and for a GPU backend that no device limit refuses (a storage binding's size is the
/// device's and not foreseen).
pub fn forecast(
    backend: &str,
    scene: &Scene,
    settings: &Settings,
    path: crate::RasterPath,
    extra: u64,
    counted: impl Fn(Rect) -> Counted,
) -> Result<Forecast, OitError> {
    let plan = Plan::new(backend, scene, settings)?.on_path(path);
    let counts = plan.needs_count() || plan.technique == crate::Technique::Reference;
    let mut out = Forecast::default();
    let tiles = windows(
        backend,
        scene,
        settings,
        extra,
        |rect, s| {
            let pixels = rect.pixels();
            let budget = host_budget(s, &plan);
            let what = format!("{} storage and outputs of a frame of {pixels} pixels", plan.technique);
            let total = |c: Counted| plan.frame_bytes(pixels, c).saturating_add(pixels.saturating_mul(extra));
            crate::plan::check_total(&what, total(Counted::default()), (&budget.0, budget.1))?;
            let c = if counts { counted(rect) } else { Counted::default() };
            crate::plan::check_total(&what, total(c), (&budget.0, budget.1))?;
            Ok((plan.storage_bytes(pixels, c) - pixels * crate::plan::RESOLVE_STATE_BYTES, total(c)))
        },
        |_, (storage, total)| {
            out.storage_bytes = out.storage_bytes.max(storage);
            out.frame_bytes = out.frame_bytes.max(total);
            Ok(())
        },
    )?;
    out.tiles = tiles.max(1) as u32;
    Ok(out)
}

/// A frame being put together from its windows, each placed as it finishes and then dropped, so
/// a tiled frame holds the whole frame's image and per-pixel outputs once
/// ([`Plan::stitched_bytes`]) and one window's frame at a time, not every window's.
struct Stitched {
    frame: Frame,
    /// Each window's counters, merged at the end ([`merge`]).
    stats: Vec<Stats>,
}

impl Stitched {
    /// A frame that ran whole.
    fn whole(frame: Frame) -> Stitched {
        Stitched { stats: Vec::new(), frame }
    }

    /// The frame of `root`, before its first window `first` is placed: per-pixel counts and
    /// losses where the first window has them (a window without them drops them, as a frame is
    /// `None` there unless every window counted).
    fn new(root: Rect, first: &Frame) -> Stitched {
        let len = root.pixels() as usize;
        Stitched {
            frame: Frame {
                image: Image::new(root.width, root.height, [0, 0, 0, 255]),
                layers: first.layers.as_ref().map(|_| vec![0; len]),
                lost_pixels: first.lost_pixels.as_ref().map(|_| vec![0; len]),
                stats: Stats::default(),
            },
            stats: Vec::new(),
        }
    }

    /// Copies the window `rect`'s frame `f` into its place.
    fn place(&mut self, root: Rect, rect: Rect, f: Frame) -> Result<(), OitError> {
        let len = rect.pixels() as usize;
        let bad_len = |v: &Option<Vec<u32>>| v.as_ref().is_some_and(|v| v.len() != len);
        if f.image.width != rect.width
            || f.image.height != rect.height
            || bad_len(&f.layers)
            || bad_len(&f.lost_pixels)
        {
            return Err(OitError::Device(format!(
                "a screen tile of {}x{} came back as a {}x{} frame",
                rect.width, rect.height, f.image.width, f.image.height
            )));
        }
        place(root, &mut self.frame.image.pixels, [(rect, &f.image.pixels[..])].into_iter());
        for (out, part) in
            [(&mut self.frame.layers, &f.layers), (&mut self.frame.lost_pixels, &f.lost_pixels)]
        {
            match part {
                Some(values) => {
                    if let Some(out) = out.as_mut() {
                        place(root, out, [(rect, &values[..])].into_iter());
                    }
                }
                None => *out = None,
            }
        }
        self.stats.push(f.stats);
        Ok(())
    }

    /// The frame put together: the windows' counters merged (none to merge where it ran whole).
    fn finish(mut self) -> Frame {
        if !self.stats.is_empty() {
            self.frame.stats = merge(self.stats.iter());
        }
        self.frame
    }
}

/// The error for a budget that cannot hold what a frame in screen tiles keeps of the whole frame
/// (its stitched image and per-pixel outputs) beside a window of one pixel.
fn too_small_to_stitch(settings: &Settings, root: Rect, needed: u64, budget: u64) -> OitError {
    OitError::TooLarge {
        what: format!(
            "{} at {}x{} in screen tiles: the stitched image and per-pixel outputs, and a tile of one pixel",
            settings.technique, root.width, root.height
        ),
        needed,
        limit_name: "the memory budget (--memory)".into(),
        limit: budget,
        hint: "raise --memory or use a smaller --size: a frame in tiles keeps its whole image and \
               per-pixel outputs while the tiles run"
            .into(),
    }
}

/// The error for a budget one pixel does not fit.
fn too_small(settings: &Settings, needed: u64, budget: u64) -> OitError {
    OitError::TooLarge {
        what: format!("{} storage and outputs of one pixel", settings.technique),
        needed,
        limit_name: "the memory budget (--memory)".into(),
        limit: budget,
        hint: "raise --memory, or use a technique with less storage a pixel (fewer slots, fabs:K)".into(),
    }
}

/// The error for a window of one pixel that was refused: the refusal itself, which names what
/// does not fit, and that screen tiles cannot make it fit. (It was wrapped as "storage and outputs
/// of one pixel needs 0 bytes, over the memory budget = 18446744073709551615 bytes" where a scene's
/// triangles were past a device's storage binding: the hostile re-run of 2026-12-05.)
fn one_pixel_refused(e: OitError) -> OitError {
    match e {
        OitError::TooLarge { what, needed, limit_name, limit, hint } => OitError::TooLarge {
            what,
            needed,
            limit_name,
            limit,
            hint: format!("{hint} (refused for a screen tile of one pixel: tiles cannot make it fit)"),
        },
        other => other,
    }
}

/// The error for a budget that needs more than [`MAX_TILES`] windows.
fn too_many(settings: &Settings, needed: u64, budget: u64) -> OitError {
    OitError::TooLarge {
        what: format!(
            "{} storage and outputs of a {}x{} frame",
            settings.technique, settings.width, settings.height
        ),
        needed,
        limit_name: format!("the memory budget (--memory) in at most {MAX_TILES} screen tiles"),
        limit: budget.saturating_mul(MAX_TILES as u64),
        hint: "raise --memory, or use a smaller --size or a technique with less storage a pixel".into(),
    }
}

/// Copies each window's rows into their place in `out`, the rows of `root`.
fn place<'a, T: Copy + 'a>(root: Rect, out: &mut [T], parts: impl Iterator<Item = (Rect, &'a [T])>) {
    let stride = root.width as usize;
    for (rect, values) in parts {
        let w = rect.width as usize;
        for (row, src) in values.chunks_exact(w).enumerate() {
            let at = (rect.y - root.y) as usize * stride + row * stride + (rect.x - root.x) as usize;
            out[at..at + w].copy_from_slice(src);
        }
    }
}

/// The counters of a frame run in windows: counts add up, `max_layers` and `storage_bytes` are
/// the largest window's (windows run one after another), device times add up (per pass by name).
pub fn merge<'a>(stats: impl Iterator<Item = &'a Stats>) -> Stats {
    let mut out = Stats::default();
    for s in stats {
        out.geometry_passes += s.geometry_passes;
        out.fragments += s.fragments;
        out.captured += s.captured;
        out.lost += s.lost;
        out.occluded += s.occluded;
        out.opaque_fragments += s.opaque_fragments;
        out.masked += s.masked;
        out.merged += s.merged;
        out.tied += s.tied;
        out.quantized += s.quantized;
        out.storage_bytes = out.storage_bytes.max(s.storage_bytes);
        out.wall_ms += s.wall_ms;
        out.gpu_ms = match (out.gpu_ms, s.gpu_ms) {
            (Some(a), Some(b)) => Some(a + b),
            (a, b) => a.or(b),
        };
        out.max_layers = out.max_layers.max(s.max_layers);
        for (name, ms) in &s.gpu_pass_ms {
            match out.gpu_pass_ms.iter_mut().find(|(n, _)| n == name) {
                Some((_, total)) => *total += ms,
                None => out.gpu_pass_ms.push((name.clone(), *ms)),
            }
        }
        out.tiles += s.tiles.max(1);
        // what a tile says it did with the samples (`Stats::count_packing` keeps plain's)
        out.coverage = out.coverage.or(s.coverage);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(width: u32, height: u32) -> Rect {
        Rect { x: 0, y: 0, width, height }
    }

    /// Tiles cover the area once each, and each fits.
    #[test]
    fn grids_cover_and_fit() {
        for (w, h, max) in [(512, 512, 70_000u64), (100, 7, 30), (1, 1000, 64), (333, 1, 1), (16, 16, 256)] {
            let tiles = grid(area(w, h), |p| p <= max).expect("fits");
            let mut seen = vec![0u8; (w * h) as usize];
            for t in &tiles {
                assert!(t.pixels() <= max, "{t:?} over {max}");
                for y in t.y..t.y + t.height {
                    for x in t.x..t.x + t.width {
                        seen[(y * w + x) as usize] += 1;
                    }
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{w}x{h} at {max}: {tiles:?}");
        }
        assert_eq!(grid(area(512, 512), |p| p <= 70_000).unwrap().len(), 4);
        assert_eq!(grid(area(16, 16), |_| true).unwrap(), [area(16, 16)]);
        assert!(grid(area(4, 4), |_| false).is_none());
        assert!(grid(area(4096, 4096), |p| p <= 16).is_none(), "over MAX_TILES");
    }

    #[test]
    fn a_refusal_splits_by_its_ratio() {
        let refusal = |needed, limit| OitError::TooLarge {
            what: "slots".into(),
            needed,
            limit_name: "a binding".into(),
            limit,
            hint: String::new(),
        };
        let r = Rect { x: 100, y: 40, width: 1000, height: 1000 };
        let tiles = split(r, &refusal(350, 100));
        // 1e6 / 3.5 × 0.85 = 242,857 pixels a tile at most: 2 × 2 tiles hold 250,000 each (over),
        // so more than four, each under the bound, covering r
        assert!(tiles.len() > 4 && tiles.len() <= 9, "{}", tiles.len());
        assert!(tiles.iter().all(|t| t.pixels() <= 242_857), "{tiles:?}");
        assert_eq!(tiles.iter().map(Rect::pixels).sum::<u64>(), r.pixels());
        assert!(
            tiles.iter().all(|t| t.x >= 100 && t.y >= 40 && t.x + t.width <= 1100 && t.y + t.height <= 1040)
        );
        // no ratio (a refusal of another kind, or needed under the limit): quarters
        assert_eq!(split(r, &refusal(50, 100)), r.quarters());
        assert_eq!(split(r, &OitError::Device("lost".into())), r.quarters());
        // just over: halves (each 500,000 ≤ 1e6 / 1.01 × 0.85), not quarters
        assert_eq!(split(r, &refusal(101, 100)).len(), 2);
    }

    #[test]
    fn quarters_split_every_shape() {
        let r = Rect { x: 3, y: 5, width: 5, height: 1 };
        assert_eq!(
            r.quarters(),
            [Rect { x: 3, y: 5, width: 3, height: 1 }, Rect { x: 6, y: 5, width: 2, height: 1 }]
        );
        let q = Rect { x: 0, y: 0, width: 3, height: 3 }.quarters();
        assert_eq!(q.iter().map(Rect::pixels).sum::<u64>(), 9);
        assert_eq!(q.len(), 4);
    }

    #[test]
    fn stats_merge() {
        let a = Stats {
            geometry_passes: 3,
            fragments: 10,
            captured: 9,
            lost: 1,
            quantized: 9,
            storage_bytes: 100,
            max_layers: 4,
            gpu_ms: Some(1.0),
            gpu_pass_ms: vec![("count".into(), 0.5)],
            ..Stats::default()
        };
        let b = Stats {
            geometry_passes: 2,
            fragments: 5,
            captured: 5,
            quantized: 5,
            storage_bytes: 80,
            max_layers: 6,
            gpu_ms: Some(2.0),
            gpu_pass_ms: vec![("count".into(), 0.25)],
            ..Stats::default()
        };
        let m = merge([&a, &b].into_iter());
        assert_eq!((m.geometry_passes, m.fragments, m.captured, m.lost, m.quantized), (5, 15, 14, 1, 14));
        assert_eq!((m.storage_bytes, m.max_layers, m.gpu_ms, m.tiles), (100, 6, Some(3.0), 2));
        assert_eq!(m.gpu_pass_ms, [("count".to_string(), 0.75)]);
    }

    #[test]
    fn a_pixel_refused_alone_says_why() {
        // The hostile re-run of 2026-12-05: a glTF scene of 45.9 M triangles on wgpu, whose
        // triangles' indices exceed the device's storage binding however small the tile, was
        // refused as "fabs:4 storage and outputs of one pixel needs 0 bytes, over the limit the
        // memory budget (--memory) = 18446744073709551615 bytes". Mutation caught: wrapping the
        // refusal in `too_small` again (its `needs 0 bytes` and the budget of u64::MAX).
        let scene = crate::builtin_scene("planes:2").unwrap().unwrap();
        let settings = Settings { width: 2, height: 2, ..Settings::default() };
        let e = run("test", &scene, &settings, |_| {
            Err(OitError::TooLarge {
                what: "the triangles' indices".into(),
                needed: 733_992_000,
                limit_name: "max_storage_buffer_binding_size".into(),
                limit: 134_217_728,
                hint: "use fewer triangles".into(),
            })
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("the triangles' indices needs 733992000 bytes"), "{e}");
        assert!(!e.contains("needs 0 bytes") && !e.contains("18446744073709551615"), "{e}");
    }
}
