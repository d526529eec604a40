//! The one reference-versus-techniques loop that `oit compare`, `oit sweep` and `oit bench` (and
//! [`crate::run_bench`]) run.
//!
//! Contract: [`Experiment::run`] frames every view of the scene first (a view that cannot be
//! framed fails before any rendering), then, for each view × backend (each backend already pinned
//! to its raster path, see [`crate::backends::with_paths`]), renders `reference` once, then each
//! technique (`warmup` untimed frames, then `frames` timed ones), and measures the last frame of
//! each against that reference with [`oit_core::metrics::accuracy`]. It returns one
//! [`Measurement`] per render: the reference's own (`baseline`), then the techniques'. A failure
//! is a measurement holding its error message, never the end of the loop; when a reference fails,
//! the techniques of that view and backend are not rendered (nothing could measure them).
//!
//! The caller sees each render start and each measurement end through [`Step`]s, as they happen
//! (a table printed row by row, a progress bar).

use std::time::Instant;

use oit_core::metrics::{Accuracy, accuracy};
use oit_core::{
    Backend, Camera, Frame, Image, OitError, Prepared, RasterPath, Scene, Settings, Stats, Technique, View,
};

/// What to measure: which backends, which techniques, how many frames each.
pub struct Experiment<'a> {
    /// Backends, each pinned to a raster path or on its own default.
    pub backends: &'a [Box<dyn Backend>],
    /// Image size, shading and the rest (the technique is set per render).
    pub settings: &'a Settings,
    /// Techniques measured against the reference (`reference` itself may be one of them).
    pub techniques: &'a [Technique],
    /// Untimed frames before each technique's timed ones (the reference is rendered once).
    pub warmup: u32,
    /// After them, untimed frame loops until this many milliseconds have passed: a GPU that idled
    /// between rows (the bench's own CPU work) clocks down, and a few frames do not bring it back
    /// up (on the H200, a bunny row's every pass measured 2.2× slower after such a gap).
    pub warmup_ms: u32,
    /// Timed frames per technique (at least 1); the last one is measured.
    pub frames: u32,
    /// Keep each measured frame's image (and the reference's per-pixel layer counts), for contact
    /// sheets and cross-backend comparisons; without, only the numbers are kept.
    pub keep_images: bool,
}

/// One render: where it ran, what, and what came of it.
#[derive(Clone, Debug)]
pub struct Measurement {
    /// Index of the backend in [`Experiment::backends`].
    pub backend_index: usize,
    /// The backend's name.
    pub backend: String,
    /// The raster path the render took.
    pub raster: RasterPath,
    /// The scene's name.
    pub scene: String,
    /// The camera's angles.
    pub view: View,
    /// The technique.
    pub technique: Technique,
    /// `true` for the reference the techniques of this view and backend are measured against.
    pub baseline: bool,
    /// The numbers, or why there are none.
    pub result: Result<Measured, String>,
    /// The technique was refused under these settings (`OitError::Unsupported` or
    /// `InvalidSettings`: a combination this backend, path or technique does not do), not failed:
    /// a command running the whole catalogue (`-t all`) lists it and goes on.
    pub refused: bool,
}

impl Measurement {
    /// `backend` or `backend/path` (as [`crate::label`]).
    pub fn label(&self) -> String {
        label_of(&self.backend, self.raster)
    }
}

/// `name` or `name/path`: how a backend on a raster path is labelled.
pub(crate) fn label_of(backend: &str, raster: RasterPath) -> String {
    let path = raster.to_string();
    if path == backend { path } else { format!("{backend}/{path}") }
}

/// The numbers of one successful render.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The last frame's counters.
    pub stats: Stats,
    /// Against the reference; `None` for the reference itself.
    pub accuracy: Option<Accuracy>,
    /// Wall milliseconds of each timed frame, its image read back to the host (the backend's own
    /// where it keeps one, else the time around the call): `readback_wall_ms` in the report.
    pub wall_ms: Vec<f64>,
    /// Wall milliseconds of each steady-state frame: the same prepared scene after the warm-up,
    /// in a frame loop ([`Prepared::frame_loop`]: frames in flight where the backend keeps them,
    /// counters read back, no image), the time between one frame's completion and the next's:
    /// `steady_wall_ms` in the report. Empty for a single untimed render.
    pub steady_wall_ms: Vec<f64>,
    /// Wall milliseconds of each frame rendered on its own and waited for before the next
    /// starts ([`Prepared::frame_stats`]): the steady state's latency, `latency_wall_ms` in the
    /// report; the steady figures themselves where the backend keeps one frame in flight.
    pub latency_wall_ms: Vec<f64>,
    /// Device milliseconds of each timed frame that measured them.
    pub gpu_ms: Vec<f64>,
    /// The deepest pixel, where the frame counted layers (the reference does).
    pub max_depth: Option<u32>,
    /// The last frame's image, when [`Experiment::keep_images`].
    pub image: Option<Image>,
    /// Its per-pixel layer counts, when kept and counted (the reference's coverage).
    pub layers: Option<Vec<u32>>,
}

impl Measured {
    /// The frame again (image and layers as kept; stats), for [`accuracy`] and error images.
    pub fn frame(&self) -> Option<Frame> {
        let image = self.image.clone()?;
        Some(Frame { image, layers: self.layers.clone(), lost_pixels: None, stats: self.stats.clone() })
    }
}

/// What [`Experiment::run`] reports as it goes.
#[derive(Clone, Copy, Debug)]
pub enum Step<'a> {
    /// A render is about to start: a description (`30.0°: dp on wgpu/compute`).
    Rendering(&'a str),
    /// A render (or its failure) was measured.
    Measured(&'a Measurement),
}

/// The frames of one technique: the last frame and the wall and GPU times of the timed ones.
pub(crate) struct Timed {
    /// The last frame.
    pub frame: Frame,
    /// Wall milliseconds per timed frame, image read back.
    pub wall: Vec<f64>,
    /// Wall milliseconds per steady-state frame of a frame loop, no image read back.
    pub steady: Vec<f64>,
    /// Wall milliseconds per frame rendered and waited for on its own, no image read back.
    pub latency: Vec<f64>,
    /// Device milliseconds per timed frame that has them.
    pub gpu: Vec<f64>,
}

/// Renders `warmup.0` untimed frames and untimed frame loops for `warmup.1` ms, then `frames` (at least 1) timed steady-state frames without
/// their image in a frame loop ([`Prepared::frame_loop`], frames in flight where the backend keeps
/// them), then as many one at a time where it does ([`Prepared::frame_stats`]), then `frames`
/// timed frames with their image, all of one prepared scene: the timed frames reuse the storage
/// and pipelines the warm-up or an earlier technique made, as a frame loop does.
pub(crate) fn measure(
    prepared: &mut dyn Prepared,
    camera: &Camera,
    settings: &Settings,
    warmup: (u32, u32),
    frames: u32,
) -> Result<Timed, OitError> {
    for _ in 0..warmup.0 {
        prepared.frame(camera, settings)?;
    }
    let cameras = vec![*camera; frames.max(1) as usize];
    let warming = Instant::now();
    while warming.elapsed().as_secs_f64() * 1e3 < f64::from(warmup.1) {
        prepared.frame_loop(&cameras, settings, &mut |_, _| {})?;
    }
    let mut done = Vec::with_capacity(cameras.len());
    let start = Instant::now();
    prepared.frame_loop(&cameras, settings, &mut |_, _| done.push(Instant::now()))?;
    let steady = loop_frame_ms(start, &done, prepared.frames_in_flight());
    let latency = if prepared.frames_in_flight() > 1 {
        let mut latency = Vec::with_capacity(cameras.len());
        for camera in &cameras {
            let start = Instant::now();
            let stats = prepared.frame_stats(camera, settings)?;
            latency.push(wall_of(&stats, start));
        }
        latency
    } else {
        // one frame at a time: the loop's frames are these
        steady.clone()
    };
    let (mut wall, mut gpu) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..frames.max(1) {
        let start = Instant::now();
        let frame = prepared.frame(camera, settings)?;
        wall.push(wall_of(&frame.stats, start));
        if let Some(g) = frame.stats.gpu_ms {
            gpu.push(g);
        }
        last = Some(frame);
    }
    let frame = last.ok_or_else(|| OitError::InvalidSettings("no frame was timed".into()))?;
    Ok(Timed { frame, wall, steady, latency, gpu })
}

/// A frame's wall milliseconds: the backend's own where it keeps one, else ours since `start`,
/// around the call.
fn wall_of(stats: &oit_core::Stats, start: Instant) -> f64 {
    if stats.wall_ms > 0.0 { stats.wall_ms } else { start.elapsed().as_secs_f64() * 1e3 }
}

/// Wall milliseconds per frame of a frame loop that started at `start` and whose frames completed
/// at `done`, with `in_flight` frames submitted at once. One at a time, each frame's time is the
/// interval since the previous completion (the first, since the start). In flight, completions
/// come in bunches (waiting for one frame may find the next done too), so each figure is the
/// mean interval over `in_flight` consecutive completions, from the first completion on: the
/// loop's filling, the first frame's latency, is left out.
pub(crate) fn loop_frame_ms(start: Instant, done: &[Instant], in_flight: usize) -> Vec<f64> {
    let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
    let w = in_flight.max(1);
    if w == 1 {
        return std::iter::once(start)
            .chain(done.iter().copied())
            .zip(done)
            .map(|(a, &b)| ms(a, b))
            .collect();
    }
    if done.len() > w {
        done.windows(w + 1).map(|pair| ms(pair[0], pair[w]) / w as f64).collect()
    } else {
        // too few frames to leave the filling out
        done.last().map(|&end| vec![ms(start, end) / done.len() as f64]).unwrap_or_default()
    }
}

impl Experiment<'_> {
    /// Renders per view: one reference and each technique per backend.
    pub fn renders_per_view(&self) -> u64 {
        self.backends.len() as u64 * (self.techniques.len() as u64 + 1)
    }

    /// Runs the loop over `views` of `scene` (named `scene_name` in the measurements), calling
    /// `on_step` before each render and after each measurement.
    pub fn run(
        &self,
        scene_name: &str,
        scene: &Scene,
        views: &[View],
        on_step: &mut dyn FnMut(Step<'_>),
    ) -> Result<Vec<Measurement>, OitError> {
        if self.frames == 0 {
            return Err(OitError::InvalidSettings("an experiment needs at least 1 timed frame".into()));
        }
        if self.backends.is_empty() {
            return Err(OitError::InvalidSettings("an experiment needs at least one backend".into()));
        }
        let base = Settings { technique: Technique::Reference, ..self.settings.clone() };
        base.validate()?;
        scene.validate()?;
        let aspect = base.width as f32 / base.height as f32;
        // Every camera first, so a view that cannot be framed fails before any work.
        let cameras = views
            .iter()
            .map(|&view| Camera::orbit_scene(scene, view, aspect))
            .collect::<Result<Vec<_>, _>>()?;

        // Each backend prepares the scene once, on first use, for every view and technique.
        let mut prepared: Vec<Option<Result<Box<dyn Prepared + '_>, String>>> =
            self.backends.iter().map(|_| None).collect();
        let mut out = Vec::new();
        for (&view, camera) in views.iter().zip(&cameras) {
            let at = if views.len() > 1 { format!("{:.1}°: ", view.azimuth) } else { String::new() };
            for (backend_index, backend) in self.backends.iter().enumerate() {
                let backend = backend.as_ref();
                let row = |technique: Technique, raster: RasterPath, baseline, result| Measurement {
                    backend_index,
                    backend: backend.name().to_string(),
                    raster,
                    scene: scene_name.to_string(),
                    view,
                    technique,
                    baseline,
                    result,
                    refused: false,
                };

                let raster = backend.raster_path(&base);
                on_step(Step::Rendering(&format!("{at}reference on {}", label_of(backend.name(), raster))));
                let ready = prepared[backend_index]
                    .get_or_insert_with(|| backend.prepare(scene).map_err(|e| e.to_string()));
                let ready = match ready {
                    Ok(p) => p.as_mut(),
                    Err(e) => {
                        out.push(row(Technique::Reference, raster, true, Err(e.clone())));
                        on_step(Step::Measured(out.last().expect("just pushed")));
                        continue;
                    }
                };
                let reference = ready.frame(camera, &base);
                let measured = reference.as_ref().map(|frame| self.numbers(frame, None, vec![], vec![]));
                out.push(row(Technique::Reference, raster, true, measured.map_err(ToString::to_string)));
                on_step(Step::Measured(out.last().expect("just pushed")));
                let Ok(reference) = reference else { continue };

                for &technique in self.techniques {
                    let settings = Settings { technique, ..base.clone() };
                    let raster = backend.raster_path(&settings);
                    on_step(Step::Rendering(&format!(
                        "{at}{technique} on {}",
                        label_of(backend.name(), raster)
                    )));
                    let result =
                        measure(ready, camera, &settings, (self.warmup, self.warmup_ms), self.frames)
                            .and_then(|t| {
                                let acc = accuracy(&reference, &t.frame.image)?;
                                let mut numbers = self.numbers(&t.frame, Some(acc), t.wall, t.gpu);
                                numbers.steady_wall_ms = t.steady;
                                numbers.latency_wall_ms = t.latency;
                                Ok(numbers)
                            });
                    let refused =
                        matches!(result, Err(OitError::Unsupported { .. } | OitError::InvalidSettings(_)));
                    out.push(Measurement {
                        refused,
                        ..row(technique, raster, false, result.map_err(|e| e.to_string()))
                    });
                    on_step(Step::Measured(out.last().expect("just pushed")));
                }
            }
        }
        Ok(out)
    }

    /// The numbers kept of `frame` (one untimed render when `wall` is empty: its own wall time).
    fn numbers(&self, frame: &Frame, accuracy: Option<Accuracy>, wall: Vec<f64>, gpu: Vec<f64>) -> Measured {
        let (wall, gpu) = if wall.is_empty() {
            (vec![frame.stats.wall_ms], frame.stats.gpu_ms.into_iter().collect())
        } else {
            (wall, gpu)
        };
        Measured {
            stats: frame.stats.clone(),
            accuracy,
            wall_ms: wall,
            steady_wall_ms: Vec::new(),
            latency_wall_ms: Vec::new(),
            gpu_ms: gpu,
            max_depth: frame.layers.as_ref().and_then(|l| l.iter().copied().max()),
            image: self.keep_images.then(|| frame.image.clone()),
            layers: if self.keep_images { frame.layers.clone() } else { None },
        }
    }
}

#[cfg(all(test, feature = "cpu"))]
mod tests {
    use super::*;

    /// A loop's frame times: one at a time, the intervals from the start; in flight, the mean
    /// over each two completions, so a bunch (two frames done at one wait) reads as two frames of
    /// half its time, and the first frame's latency is left out.
    #[test]
    fn loop_frame_times() {
        let t0 = Instant::now();
        let at = |ms: u64| t0 + std::time::Duration::from_millis(ms);
        let one = loop_frame_ms(t0, &[at(5), at(9), at(14)], 1);
        assert_eq!(one.iter().map(|x| x.round() as u64).collect::<Vec<_>>(), [5, 4, 5]);
        // completions bunched in pairs 8 ms apart: 4 ms a frame
        let two = loop_frame_ms(t0, &[at(10), at(10), at(18), at(18), at(26), at(26)], 2);
        assert_eq!(two.iter().map(|x| x.round() as u64).collect::<Vec<_>>(), [4, 4, 4, 4]);
        // too few frames: the whole loop's mean
        assert_eq!(
            loop_frame_ms(t0, &[at(6), at(8)], 2).iter().map(|x| x.round() as u64).collect::<Vec<_>>(),
            [4]
        );
        assert!(loop_frame_ms(t0, &[], 2).is_empty());
    }

    #[test]
    fn reference_once_per_view_and_backend_then_each_technique() {
        let backends: Vec<Box<dyn Backend>> = vec![Box::new(oit_cpu::CpuBackend::default())];
        let settings = Settings { width: 16, height: 16, ..Settings::default() };
        let techniques = [Technique::Dp, Technique::WeightedAverage];
        let exp = Experiment {
            backends: &backends,
            settings: &settings,
            techniques: &techniques,
            warmup: 0,
            warmup_ms: 0,
            frames: 1,
            keep_images: false,
        };
        let scene = oit_core::load_scene("planes:4").unwrap();
        let views = [View { azimuth: 0.0, ..View::default() }, View { azimuth: 90.0, ..View::default() }];
        let (mut started, mut done) = (0u64, 0u64);
        let rows = exp
            .run("planes:4", &scene, &views, &mut |step| match step {
                Step::Rendering(_) => started += 1,
                Step::Measured(_) => done += 1,
            })
            .unwrap();
        assert_eq!(rows.len() as u64, 2 * exp.renders_per_view());
        assert_eq!((started, done), (rows.len() as u64, rows.len() as u64));
        let first = &rows[..3];
        assert!(first[0].baseline && first[0].technique == Technique::Reference);
        assert_eq!(first[0].result.as_ref().unwrap().max_depth, Some(4));
        assert!(first[0].result.as_ref().unwrap().accuracy.is_none());
        assert_eq!(first[1].technique, Technique::Dp);
        let dp = first[1].result.as_ref().unwrap();
        assert_eq!(dp.accuracy.unwrap().epr, 0.0);
        assert_eq!(dp.stats.geometry_passes, 5);
        assert!(dp.image.is_none());
        assert_eq!(rows[3].view.azimuth, 90.0);
        assert_eq!(first[1].label(), "cpu");
    }

    #[test]
    fn a_failing_technique_is_a_row_and_the_rest_go_on() {
        let backends: Vec<Box<dyn Backend>> = vec![Box::new(oit_cpu::CpuBackend::default())];
        // the weighted techniques never order fragments, so they cannot absorb through a thickness
        let settings =
            Settings { width: 16, height: 16, effect: oit_core::Effect::Translucency, ..Settings::default() };
        let techniques = [Technique::WeightedAverage, Technique::Dp];
        let exp = Experiment {
            backends: &backends[..1],
            settings: &settings,
            techniques: &techniques,
            warmup: 0,
            warmup_ms: 0,
            frames: 1,
            keep_images: true,
        };
        let scene = oit_core::load_scene("planes:2").unwrap();
        let rows = exp.run("planes:2", &scene, &[View::default()], &mut |_| {}).unwrap();
        assert_eq!(rows.len(), 3);
        assert!(rows[1].result.is_err());
        let dp = rows[2].result.as_ref().unwrap();
        assert!(dp.image.is_some() && dp.frame().is_some());
        assert!(rows[0].result.as_ref().unwrap().layers.is_some());
    }

    #[test]
    fn a_view_that_cannot_be_framed_fails_before_any_render() {
        let backends: Vec<Box<dyn Backend>> = vec![Box::new(oit_cpu::CpuBackend::default())];
        let settings = Settings { width: 16, height: 16, ..Settings::default() };
        let exp = Experiment {
            backends: &backends,
            settings: &settings,
            techniques: &[Technique::Dp],
            warmup: 0,
            warmup_ms: 0,
            frames: 1,
            keep_images: false,
        };
        let scene = oit_core::load_scene("planes:2").unwrap();
        let bad = View { fov: f32::NAN, ..View::default() };
        let mut renders = 0;
        let result = exp.run("planes:2", &scene, &[View::default(), bad], &mut |_| renders += 1);
        assert!(result.is_err());
        assert_eq!(renders, 0);
    }
}
