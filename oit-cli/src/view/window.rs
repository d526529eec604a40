//! The window: winit's event loop, a wgpu surface, and each frame drawn by oit-wgpu's embeddable
//! pass ([`render_frame`], the one place the viewer uses it), then the overlay and the present.
//!
//! The pass renders at the window's size and returns the image; the viewer writes it (with the
//! overlay, or the error heat map when comparing) into the surface texture, which it configures
//! with `COPY_DST`. A minimised window (size 0, iconified, or unmapped) draws nothing until it is
//! restored: no frame, no present, the surface left as it was ([`drawable`]).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use oit_bench::present::{annotate_frame, draw_text, fill_rect, line_height};
use oit_core::metrics::{Accuracy, accuracy, error_image};
use oit_core::{Camera, Frame, Image, OitError, Scene, Settings, Technique};
use oit_wgpu::OitPass;
use oit_wgpu::embed::{CaptureShader, SceneGeometry};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key as WinitKey, NamedKey};
use winit::window::{Window, WindowId};

use super::keys::{self, Reaction, ViewState};
use super::script::{Action, Event};
use super::{Checked, ViewArgs};
use crate::Outcome;

/// The overlay's text size in pixels.
const OVERLAY_PX: f32 = 14.0;
/// How long a scripted `resize` waits for the window to take its size.
const RESIZE_WAIT: Duration = Duration::from_secs(5);

/// Everything the viewer asks of oit's embeddable pass, in one place: the frame's view and
/// settings, the scene's per-frame data, its opaque part (drawn by the geometry), and one frame
/// whose geometry passes draw the transparent part with a pipeline the viewer builds over oit's
/// capture module and the hardware path's vertex stage.
fn render_frame(
    pass: &mut OitPass,
    geometry: &SceneGeometry,
    device: &wgpu::Device,
    scene: &Scene,
    camera: Camera,
    settings: &Settings,
) -> Result<Frame, OitError> {
    pass.set_view(settings.clone(), camera)?;
    geometry.write_frame(scene, &camera, settings);
    // the scene's opaque part first, into the geometry's depth and colour, which the pass cuts
    // at and composites over
    geometry.draw_opaque_for(pass)?;
    pass.frame(
        None,
        |capture| scene_pipeline(device, geometry, capture),
        |rpass, _| {
            rpass.set_bind_group(1, geometry.bind_group(), &[]);
            rpass.draw(0..geometry.vertex_count(), 0..1);
        },
    )
}

/// The viewer's render pipeline for one capture module: oit's module, then the hardware path's
/// vertex and fragment stages (`hw_vs`, and `hw_fs` or, multisampled, `hw_fs_masked`), the
/// capture's multisample state, no vertex buffers, no culling.
fn scene_pipeline(
    device: &wgpu::Device,
    geometry: &SceneGeometry,
    capture: &CaptureShader<'_>,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("oit view"),
        source: wgpu::ShaderSource::Wgsl(
            format!("{}\n{}\n{}", capture.wgsl, SceneGeometry::WGSL, SceneGeometry::WGSL_MASKED).into(),
        ),
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("oit view"),
        bind_group_layouts: &[Some(capture.bind_group_layout), Some(geometry.bind_group_layout())],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("oit view"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("hw_vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: None,
        multisample: capture.multisample,
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(SceneGeometry::fragment_entry(capture)),
            compilation_options: Default::default(),
            targets: &[Some(capture.count_target.clone())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Whether a frame can be drawn into the window: not minimised (iconified, as a window manager
/// reports it), mapped, and of a size above 0 × 0 (a minimised window's size on some platforms).
fn drawable(window: &Window) -> bool {
    let size = window.inner_size();
    size.width > 0
        && size.height > 0
        && window.is_minimized() != Some(true)
        && window.is_visible() != Some(false)
}

/// The device, the surface and what oit keeps on the device.
struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    adapter_name: String,
    geometry: SceneGeometry,
    pass: OitPass,
    /// Errors wgpu reports outside an error scope (instead of its default, a panic).
    device_errors: Arc<Mutex<Vec<String>>>,
}

/// The device features oit-wgpu uses when the adapter has them (timestamps for the GPU time,
/// 32-bit float blending for the fragment counts, the adapter's format features for 8 samples),
/// as oit-wgpu's own device asks for them.
fn optional_features() -> wgpu::Features {
    wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
        | wgpu::Features::FLOAT32_BLENDABLE
        // whether the count target takes 8 samples a pixel (`OitPass::with_adapter`)
        | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
}

impl Gfx {
    /// Opens the window, a Vulkan adapter that can present to it, the device, the surface, the
    /// scene's geometry and the pass.
    fn new(
        event_loop: &ActiveEventLoop,
        checked: &Checked,
        adapter_filter: Option<&str>,
    ) -> Result<Gfx, OitError> {
        let device_error = |what: String| OitError::Device(what);
        let (w, h) = (checked.settings.width, checked.settings.height);
        let attributes =
            Window::default_attributes().with_title("oit view").with_inner_size(PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| device_error(format!("cannot open a window: {e}")))?,
        );
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let surface = instance.create_surface(window.clone()).map_err(|e| {
            device_error(format!("cannot make a wgpu surface of the window: {e}; {INSTALL_VULKAN}"))
        })?;
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
        if adapters.is_empty() {
            return Err(no_vulkan());
        }
        let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
        let filter = adapter_filter.map(str::to_owned).or_else(|| std::env::var("OIT_ADAPTER").ok());
        let mut usable: Vec<wgpu::Adapter> = adapters
            .into_iter()
            .filter(|a| {
                filter.as_ref().is_none_or(|f| a.get_info().name.to_lowercase().contains(&f.to_lowercase()))
            })
            .filter(|a| a.is_surface_supported(&surface))
            .filter(|a| a.features().contains(oit_wgpu::required_features()))
            .collect();
        usable.sort_by_key(|a| a.get_info().device_type != wgpu::DeviceType::DiscreteGpu);
        let adapter = usable.into_iter().next().ok_or_else(|| {
            device_error(format!(
                "no adapter{} can present to the window with the features oit-wgpu needs; adapters found: {}",
                filter.as_ref().map(|f| format!(" matching '{f}'")).unwrap_or_default(),
                names.join(", ")
            ))
        })?;
        let info = adapter.get_info();
        let features = oit_wgpu::required_features() | (optional_features() & adapter.features());
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("oit view"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| device_error(format!("cannot open '{}': {e}", info.name)))?;
        let device_errors: Arc<Mutex<Vec<String>>> = Arc::default();
        let sink = device_errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut errors) = sink.lock() {
                errors.push(e.to_string());
            }
        }));
        let caps = surface.get_capabilities(&adapter);
        use wgpu::TextureFormat as F;
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| matches!(f, F::Bgra8Unorm | F::Rgba8Unorm | F::Bgra8UnormSrgb | F::Rgba8UnormSrgb))
            .ok_or_else(|| {
                device_error(format!("the window's surface offers no 8-bit RGBA format: {:?}", caps.formats))
            })?;
        if !caps.usages.contains(wgpu::TextureUsages::COPY_DST) {
            return Err(device_error(format!(
                "the window's surface on '{}' cannot be copied into (usages {:?}), which the viewer needs",
                info.name, caps.usages
            )));
        }
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: Vec::new(),
        };
        if size.width > 0 && size.height > 0 {
            surface.configure(&device, &config);
        }
        let scene = &checked.scene;
        let geometry = SceneGeometry::new(&device, &queue, scene)?;
        let camera = Camera::orbit_scene(scene, checked.state.view, w as f32 / h as f32)?;
        // the scene's bounds and absorption, and its instances' boxes for bdp and adp
        let pass = OitPass::new(&device, &queue, checked.settings.clone(), camera)?
            .with_scene_geometry(&geometry)
            .with_adapter(&adapter);
        Ok(Gfx {
            window,
            surface,
            device,
            queue,
            config,
            adapter_name: info.name,
            geometry,
            pass,
            device_errors,
        })
    }

    /// The first error wgpu reported outside an error scope since the last call.
    fn take_device_error(&self) -> Option<String> {
        self.device_errors.lock().ok().and_then(|mut e| if e.is_empty() { None } else { Some(e.remove(0)) })
    }

    /// Writes `image` into the surface's next texture and presents it; reconfigures the surface
    /// when it is outdated and skips the frame when none is available.
    fn present(&mut self, image: &Image) {
        if (self.config.width, self.config.height) != (image.width, image.height) {
            self.config.width = image.width;
            self.config.height = image.height;
            self.surface.configure(&self.device, &self.config);
        }
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.device, &self.config);
                return;
            }
            _ => return,
        };
        let target = &texture.texture;
        if target.width() < image.width || target.height() < image.height {
            return;
        }
        let bgra =
            matches!(target.format(), wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
        let bytes: Vec<u8> = image
            .pixels
            .iter()
            .flat_map(|p| if bgra { [p[2], p[1], p[0], 255] } else { [p[0], p[1], p[2], 255] })
            .collect();
        self.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: target,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(image.width * 4),
                rows_per_image: Some(image.height),
            },
            wgpu::Extent3d { width: image.width, height: image.height, depth_or_array_layers: 1 },
        );
        self.queue.submit([]);
        self.window.pre_present_notify();
        self.queue.present(texture);
    }
}

/// The last frame drawn: what a screenshot writes and what the overlay reports.
struct Drawn {
    /// The technique's image as `oit render` writes it (the complexity legend included), no
    /// overlay.
    image: Image,
    /// The `oit render` options of this view.
    options: String,
    /// Its numbers, when the frame was drawn.
    frame: Option<Frame>,
    /// The comparison with the reference, when on.
    accuracy: Option<Accuracy>,
    /// Wall time of the frame in ms (the pass, the comparison, the overlay and the present).
    frame_ms: f64,
}

/// The viewer's state between events.
struct App<'a> {
    checked: Checked,
    args: &'a ViewArgs,
    gfx: Option<Gfx>,
    /// A fatal error: the loop exits and `run` returns it.
    fatal: Option<OitError>,
    /// Errors reported as `error:` lines (the run then ends as failed when it is scripted).
    reported: Vec<String>,
    /// A note for the overlay (the last key's answer, the last error).
    note: Option<String>,
    drawn: Option<Drawn>,
    /// When the first frame was drawn (the script's clock starts there).
    started: Option<Instant>,
    next_event: usize,
    /// A scripted screenshot to write once the next frame is drawn.
    pending_shot: Option<PathBuf>,
    /// A scripted resize waited for: its size and when the wait ends.
    pending_resize: Option<(u32, u32, Instant)>,
    /// The script minimised the window (and has not restored it).
    minimized: bool,
    /// With `--screenshot`: the script's last event has run without a `quit`, so the next frame
    /// drawn is the last (a script without `quit`, or an empty one, never ended: issue 41.5).
    script_done: bool,
    /// Whether F12 asked for a screenshot.
    want_shot: bool,
    /// The left button is down at this cursor position.
    drag_from: Option<(f64, f64)>,
    cursor: (f64, f64),
    shift: bool,
    dirty: bool,
}

impl App<'_> {
    /// Reports an error once as an `error:` line and on the overlay, keeping the window open.
    fn report(&mut self, message: String) {
        if !self.reported.contains(&message) {
            crate::output::error_line(&message);
            self.reported.push(message.clone());
        }
        self.note = Some(message);
    }

    /// Answers a key, from the keyboard or the script.
    fn key(&mut self, event_loop: &ActiveEventLoop, name: &str, shift: bool) {
        let Some(key) = keys::lookup(name) else {
            return;
        };
        self.note = None;
        match self.checked.state.key(key, shift) {
            Reaction::Redraw => self.dirty = true,
            Reaction::Screenshot => {
                self.want_shot = true;
                self.dirty = true;
            }
            Reaction::Quit => event_loop.exit(),
            Reaction::Note(text) => {
                self.note = Some(text);
                self.dirty = true;
            }
        }
    }

    /// Draws one frame at the window's size: the pass, the comparison when on, the overlay, the
    /// present. Nothing while minimised.
    fn draw(&mut self) {
        let Some(gfx) = self.gfx.as_mut() else {
            return;
        };
        if !drawable(&gfx.window) {
            return;
        }
        let size = gfx.window.inner_size();
        let start = Instant::now();
        let state = &self.checked.state;
        let settings = Settings {
            width: size.width,
            height: size.height,
            technique: state.technique,
            alpha: state.alpha,
            shading: state.shading,
            effect: state.effect,
            samples: state.samples,
            ..self.checked.settings.clone()
        };
        let options = state.render_options(size.width, size.height);
        let scene = &self.checked.scene;
        let result = Camera::orbit_scene(scene, state.view, size.width as f32 / size.height as f32).and_then(
            |camera| {
                let frame =
                    render_frame(&mut gfx.pass, &gfx.geometry, &gfx.device, scene, camera, &settings)?;
                let compared = if state.compare {
                    let reference_settings = Settings { technique: Technique::Reference, ..settings.clone() };
                    let reference = render_frame(
                        &mut gfx.pass,
                        &gfx.geometry,
                        &gfx.device,
                        scene,
                        camera,
                        &reference_settings,
                    )?;
                    Some((accuracy(&reference, &frame.image)?, error_image(&reference, &frame.image)))
                } else {
                    None
                };
                Ok((frame, compared))
            },
        );
        let device_error = gfx.take_device_error();
        let (image, mut shown, frame, acc) = match result {
            Ok((frame, compared)) => {
                let mut image = frame.image.clone();
                annotate_frame(&mut image, settings.effect, &frame.stats);
                let (shown, acc) = match compared {
                    Some((acc, heat)) => (heat, Some(acc)),
                    None => (image.clone(), None),
                };
                (image, shown, Some(frame), acc)
            }
            Err(e) => {
                let blank = Image::new(size.width, size.height, [0, 0, 0, 255]);
                self.report(format!("{}: {e}", state.technique));
                (blank.clone(), blank, None, None)
            }
        };
        if let Some(e) = device_error {
            self.report(format!("wgpu: {e}"));
        }
        let mut drawn = Drawn { image, options, frame, accuracy: acc, frame_ms: 0.0 };
        let previous_ms = self.drawn.as_ref().map_or(0.0, |d| d.frame_ms);
        if self.checked.state.overlay {
            let gfx = self.gfx.as_ref().expect("checked above");
            draw_overlay(
                &mut shown,
                &self.checked.state,
                &drawn,
                previous_ms,
                &gfx.adapter_name,
                self.note.as_deref(),
            );
        }
        let gfx = self.gfx.as_mut().expect("checked above");
        gfx.present(&shown);
        drawn.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        self.drawn = Some(drawn);
        self.started.get_or_insert_with(Instant::now);
        if let Some(path) = self.pending_shot.take() {
            self.write_shot(&path);
        }
        if std::mem::take(&mut self.want_shot) {
            let path = free_name();
            self.write_shot(&path);
        }
    }

    /// Writes the last frame's image to `path` and prints its `oit render` options.
    fn write_shot(&mut self, path: &Path) {
        let Some(drawn) = &self.drawn else {
            return;
        };
        let failed = drawn.frame.is_none();
        match drawn.image.save_png(path) {
            Ok(()) if !failed => {
                let line = format!("screenshot {}: {}\n", path.display(), drawn.options);
                if let Err(e) = crate::output::print(&line) {
                    self.report(e.to_string());
                }
                self.note = Some(format!("wrote {}", path.display()));
            }
            Ok(()) => self.report(format!("{}: the frame failed; the screenshot is blank", path.display())),
            Err(e) => self.report(e.to_string()),
        }
    }

    /// Runs the script's events that are due; stops at a screenshot (it needs the next frame) or
    /// a resize (until the window has its size). Returns when the next event is due.
    fn run_script(&mut self, event_loop: &ActiveEventLoop) -> Option<Instant> {
        let started = self.started?;
        if self.pending_shot.is_some() {
            // restored but not mapped yet: look again soon (the map may come without a redraw)
            if self.gfx.as_ref().is_some_and(|g| !drawable(&g.window)) {
                self.dirty = true;
                return Some(Instant::now() + Duration::from_millis(20));
            }
            return None;
        }
        if let Some((w, h, until)) = self.pending_resize {
            let size = self.gfx.as_ref().map(|g| g.window.inner_size());
            if size == Some(PhysicalSize::new(w, h))
                && self.drawn.as_ref().is_some_and(|d| d.image.width == w && d.image.height == h)
            {
                self.pending_resize = None;
            } else if Instant::now() < until {
                return Some(Instant::now() + Duration::from_millis(20));
            } else {
                self.report(format!(
                    "the window did not take the scripted size {w}x{h} within {RESIZE_WAIT:?}"
                ));
                self.pending_resize = None;
            }
        }
        while let Some(Event { time, action }) = self.checked.script.get(self.next_event).cloned() {
            let due = started + Duration::from_secs_f64(time);
            if Instant::now() < due {
                return Some(due);
            }
            self.next_event += 1;
            match action {
                Action::Key { name, shift } => self.key(event_loop, &name, shift),
                Action::Drag { dx, dy } => {
                    self.checked.state.orbit(dx, dy);
                    self.dirty = true;
                }
                Action::Scroll { lines } => {
                    self.checked.state.zoom(lines);
                    self.dirty = true;
                }
                Action::Resize { width, height } => {
                    if let Some(gfx) = &self.gfx {
                        let _ = gfx.window.request_inner_size(PhysicalSize::new(width, height));
                    }
                    self.pending_resize = Some((width, height, Instant::now() + RESIZE_WAIT));
                    self.dirty = true;
                    return Some(Instant::now() + Duration::from_millis(20));
                }
                Action::Minimize => {
                    if let Some(gfx) = &self.gfx {
                        gfx.window.set_minimized(true);
                        gfx.window.set_visible(false);
                    }
                    self.minimized = true;
                }
                Action::Restore => {
                    if let Some(gfx) = &self.gfx {
                        gfx.window.set_visible(true);
                        gfx.window.set_minimized(false);
                    }
                    self.minimized = false;
                    self.dirty = true;
                }
                Action::Screenshot(path) if self.minimized => {
                    self.report(format!(
                        "screenshot {}: the window is minimised, so no frame is drawn: `restore` it first",
                        path.display()
                    ));
                }
                Action::Screenshot(path) => {
                    self.pending_shot = Some(path);
                    self.dirty = true;
                    return None;
                }
                Action::Quit => {
                    event_loop.exit();
                    return None;
                }
            }
        }
        // every event has run: with --screenshot, draw once more (the last event's state) and
        // exit; without it the window stays open for the keys and mouse (`--help` says so)
        if self.args.screenshot.is_some() && !self.script_done {
            self.script_done = true;
            if self.minimized && self.drawn.is_some() {
                event_loop.exit();
            } else {
                self.dirty = true;
            }
        }
        None
    }
}

/// The first `oit-view-NNNN.png` in the current folder that does not exist yet.
fn free_name() -> PathBuf {
    (1..)
        .map(|n| PathBuf::from(format!("oit-view-{n:04}.png")))
        .find(|p| !p.exists())
        .expect("some name is free")
}

/// The overlay: technique, passes, fragments, lost, GPU and frame time, the settings the keys
/// change, the comparison, and the last note, on a dimmed box at the top left.
fn draw_overlay(
    image: &mut Image,
    state: &ViewState,
    drawn: &Drawn,
    frame_ms: f64,
    adapter: &str,
    note: Option<&str>,
) {
    let mut lines = vec![format!("{}   wgpu hardware (embedded pass) on {adapter}", state.technique)];
    if let Some(frame) = &drawn.frame {
        let s = &frame.stats;
        let lost = if s.fragments > 0 { 100.0 * s.lost as f64 / s.fragments as f64 } else { 0.0 };
        lines.push(format!(
            "passes {}   fragments {}   lost {} ({lost:.2}%)",
            s.geometry_passes, s.fragments, s.lost
        ));
        let gpu = s.gpu_ms.map_or("n/a".to_string(), |g| format!("{g:.2} ms"));
        lines.push(format!("GPU {gpu}   frame {frame_ms:.1} ms"));
    }
    let alpha = state.alpha.map_or("own".to_string(), |a| a.to_string());
    lines.push(format!(
        "alpha {alpha}   shading {}   effect {}   samples {}",
        state.shading_name(),
        state.effect_name(),
        state.samples
    ));
    if let Some(acc) = &drawn.accuracy {
        let epr = if acc.is_measured() {
            format!("{:.3}%", acc.epr * 100.0)
        } else {
            "n/a (nothing covered)".into()
        };
        lines.push(format!(
            "EPR {epr} vs reference ({} of {} pixels); heat map of the error x8",
            acc.error_pixels, acc.covered
        ));
    }
    if let Some(note) = note {
        lines.push(note.to_string());
    }
    lines.push(
        "T technique  K/P/M parameter  N samples  A alpha  S shading  E effect  R reference  F12 shot".into(),
    );
    let step = line_height(OVERLAY_PX) as i64 + 2;
    let width = lines.iter().map(|l| oit_bench::present::text_width(l, OVERLAY_PX)).max().unwrap_or(0);
    fill_rect(image, 0, 0, u64::from(width) + 12, (step * lines.len() as i64 + 8) as u64, [0, 0, 0, 160]);
    for (i, line) in lines.iter().enumerate() {
        draw_text(image, 6, 4 + step * i as i64, line, OVERLAY_PX, [235, 235, 235, 255]);
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        match Gfx::new(event_loop, &self.checked, self.args.adapter.as_deref()) {
            Ok(gfx) => {
                gfx.window.request_redraw();
                // N steps to 8 samples only where the device draws them
                self.checked.state.max_samples = gfx.pass.max_samples();
                self.gfx = Some(gfx);
            }
            Err(e) => {
                self.fatal = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_)
            | WindowEvent::ScaleFactorChanged { .. }
            | WindowEvent::Occluded(false) => self.dirty = true,
            WindowEvent::RedrawRequested => {
                self.dirty = false;
                self.draw();
                if self.args.screenshot.is_some()
                    && (self.args.script.is_none() || self.script_done)
                    && self.drawn.is_some()
                {
                    event_loop.exit();
                }
            }
            WindowEvent::ModifiersChanged(m) => self.shift = m.state().shift_key(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                let name = match &event.logical_key {
                    WinitKey::Character(c) => c.to_string(),
                    WinitKey::Named(NamedKey::Escape) => "Escape".into(),
                    WinitKey::Named(NamedKey::F12) => "F12".into(),
                    WinitKey::Named(NamedKey::ArrowLeft) => "Left".into(),
                    WinitKey::Named(NamedKey::ArrowRight) => "Right".into(),
                    WinitKey::Named(NamedKey::ArrowUp) => "Up".into(),
                    WinitKey::Named(NamedKey::ArrowDown) => "Down".into(),
                    _ => return,
                };
                // shift+= is + on most layouts: the character is the key
                let shift = self.shift && name.chars().all(|c| c.is_alphabetic());
                self.key(event_loop, &name, shift);
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                self.drag_from = (state == ElementState::Pressed).then_some(self.cursor);
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = (position.x, position.y);
                if let Some((x, y)) = self.drag_from {
                    self.checked.state.orbit((position.x - x) as f32, (position.y - y) as f32);
                    self.drag_from = Some(self.cursor);
                    self.dirty = true;
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.checked.state.zoom(lines);
                self.dirty = true;
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let next = self.run_script(event_loop);
        if self.dirty
            && let Some(gfx) = &self.gfx
        {
            gfx.window.request_redraw();
        }
        event_loop.set_control_flow(match next {
            Some(at) => ControlFlow::WaitUntil(at),
            None => ControlFlow::Wait,
        });
    }
}

/// The message for a machine without a display.
fn no_display(detail: &str) -> OitError {
    OitError::Device(format!(
        "no display: {detail}. oit view opens an X11 window (on Wayland through XWayland); without a \
         screen, run it under a virtual one: `xvfb-run oit view ...`"
    ))
}

/// What to install for a Vulkan driver, for every error that lacks one.
const INSTALL_VULKAN: &str = "install a Vulkan loader and driver: `apt-get install libvulkan1 \
     mesa-vulkan-drivers` (lavapipe, on the CPU, where there is no GPU driver)";

/// The viewer's error without a Vulkan driver.
fn no_vulkan() -> OitError {
    OitError::Device(format!("no Vulkan adapter found: oit view draws through Vulkan; {INSTALL_VULKAN}"))
}

/// Whether any Vulkan adapter is there to draw with (the loader present, a driver found).
fn vulkan_adapter_present() -> bool {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    !pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN)).is_empty()
}

/// Opens the window and runs until it closes, the script quits or `--screenshot` is written.
pub fn run(checked: Checked, args: &ViewArgs) -> Result<Outcome, OitError> {
    if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        return Err(no_display("DISPLAY is not set"));
    }
    // a driver first, before the window and the key list: without one, making the window's
    // surface fails with wgpu's bare "Failed to create surface for any enabled backend: {}"
    if !vulkan_adapter_present() {
        return Err(no_vulkan());
    }
    let event_loop =
        EventLoop::new().map_err(|e| no_display(&format!("cannot connect to the X server ({e})")))?;
    eprintln!("{}", keys::BINDINGS);
    let mut app = App {
        checked,
        args,
        gfx: None,
        fatal: None,
        reported: Vec::new(),
        note: None,
        drawn: None,
        started: None,
        next_event: 0,
        pending_shot: None,
        pending_resize: None,
        minimized: false,
        script_done: false,
        want_shot: false,
        drag_from: None,
        cursor: (0.0, 0.0),
        shift: false,
        dirty: true,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| OitError::Device(format!("the window's event loop failed: {e}")))?;
    if let Some(e) = app.fatal.take() {
        return Err(e);
    }
    if let Some(path) = &args.screenshot {
        if app.drawn.is_none() {
            return Err(OitError::Write { path: path.clone(), message: "no frame was drawn".into() });
        }
        app.write_shot(path);
    }
    if let Some(drawn) = &app.drawn {
        crate::output::print(&format!("view {}\n", drawn.options))?;
    }
    // a scripted or --screenshot run is a test: an error on the way is a failure
    let unattended = args.script.is_some() || args.screenshot.is_some();
    Ok(if unattended && !app.reported.is_empty() { Outcome::Failed } else { Outcome::Success })
}
