//! `oit view`: the scene in a window, drawn live by oit-wgpu's embeddable pass
//! ([`oit_wgpu::OitPass`]) with oit's own vertex stage ([`oit_wgpu::embed::SceneGeometry`], which
//! also draws a scene's opaque part first, for the pass to cut at and composite over), so its
//! image is `oit render --backend wgpu --raster hardware`'s at the same view. Keys switch the
//! technique and its parameters, the alpha, shading and effect; the mouse orbits and zooms; `R`
//! compares with the reference. `--script` replays timed key and mouse events ([`script`]), which
//! is how the viewer is tested (`tests/view.rs`, under Xvfb).

mod keys;
mod script;
mod window;

use std::path::PathBuf;

use clap::Args;
use oit_core::{Camera, OitError, Settings, Technique, View, load_scene_with, parse_rgb, parse_size};

use crate::Outcome;
use crate::options::check_output;

/// Arguments of `oit view`.
#[derive(Args, Debug)]
#[command(
    about = "Show the scene in a window, live: orbit, zoom, switch techniques and compare with the reference",
    long_about = "Show the scene in a window, live: orbit, zoom, switch techniques and compare with the reference.\n\n\
        The window is drawn by oit-wgpu's embeddable pass (OitPass) with the hardware raster's vertex \
        stage, so a screenshot equals `oit render --backend wgpu --raster hardware` at the same view \
        (on exit, and for each scripted screenshot, the view's `oit render` options are printed). \
        It needs a display (X11; on Wayland through XWayland): without one, run it under \
        `xvfb-run oit view ...`.",
    after_help = help_text()
)]
pub struct ViewArgs {
    /// The technique to start with (any the embeddable pass draws: reference, plain, dp, ddp, wavg,
    /// wsum, bdp[:P], adp, fabs[:K], mdts64[:K], mdts[:K] with --alpha, mlp:M, dfb, ll).
    #[arg(short, long, value_name = "T", default_value = "reference")]
    pub technique: String,

    /// The scene: a built-in name, a Wavefront .obj file or a glTF file (.gltf, .glb), as for
    /// `oit render`.
    #[arg(long, value_name = "NAME|FILE", default_value = oit_core::DEFAULT_SCENE)]
    pub scene: String,

    /// The scene of a glTF file to show (--scene FILE.gltf or FILE.glb), numbered from 0, as for
    /// `oit render` [default: the file's default scene].
    #[arg(long, value_name = "N")]
    pub gltf_scene: Option<usize>,

    /// The window's first size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", default_value = "768x768")]
    pub size: String,

    /// Starting camera angle around the vertical axis in degrees.
    #[arg(long, value_name = "DEG", default_value_t = 30.0, allow_negative_numbers = true)]
    pub azimuth: f32,

    /// Starting camera angle above the horizontal plane in degrees (±89).
    #[arg(long, value_name = "DEG", default_value_t = 20.0, allow_negative_numbers = true)]
    pub elevation: f32,

    /// Starting vertical field of view in degrees (zoom changes it, from 1 to 120).
    #[arg(long, value_name = "DEG", default_value_t = 45.0, allow_negative_numbers = true)]
    pub fov: f32,

    /// Opacity in [0, 1] for every object [default: each object's own].
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub alpha: Option<f32>,

    /// Starting shading: headlight, flat, vertex or normal.
    #[arg(long, value_name = "MODE", default_value = "headlight")]
    pub shading: String,

    /// Starting effect: transparency, translucency, fresnel or complexity.
    #[arg(long, value_name = "EFFECT", default_value = "transparency")]
    pub effect: String,

    /// Background colour as linear R,G,B, each in [0, 1].
    #[arg(long, value_name = "R,G,B", default_value = "0.06,0.07,0.09")]
    pub background: String,

    /// Starting samples a pixel: 1, 4 or 8 (where the device draws 8), multisampled as
    /// `oit render --samples` on the hardware path (N steps it).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub samples: u32,

    /// Stops the peeling techniques after N capture passes, as for `oit render`.
    #[arg(long, value_name = "N")]
    pub max_peels: Option<u32>,

    /// The backend: wgpu (the only one with a window: the viewer draws through oit-wgpu's
    /// embeddable pass).
    #[arg(long, value_name = "NAME", default_value = "wgpu")]
    pub backend: String,

    /// GPU adapter to use: a substring of its name; also read from OIT_ADAPTER.
    #[arg(long, value_name = "NAME")]
    pub adapter: Option<String>,

    /// No overlay (the text of technique, passes, fragments, lost and times); O toggles it.
    #[arg(long)]
    pub no_overlay: bool,

    /// Replays the timed key and mouse events of FILE (the format is below). After its last
    /// event the window stays open for the keys and mouse, unless the script ends with `quit` or
    /// --screenshot is given (then the view exits once the last event's frame is drawn).
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,

    /// Writes the last frame drawn (without the overlay) to FILE.png and exits: after the first
    /// frame, or with --script when the script quits or its last event has run (an empty script
    /// included).
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
}

/// The keys, the mouse and the script format, after the options in `oit view --help`.
fn help_text() -> String {
    format!(
        "{}\n\n\
         Script (--script FILE): one event a line, `TIME ACTION [ARGS]`, TIME in seconds from the first\n\
         frame (events run in order, each no earlier than its time), `#` starts a comment:\n  \
         0.5 key T             a key press (key shift+T, key F12, key Left, key Plus, ...)\n  \
         1.0 drag 40 -20       a left-button drag in pixels (orbit)\n  \
         1.5 scroll 2          the wheel in lines (zoom; negative zooms out)\n  \
         2.0 resize 320 240    the window's inner size, waited for\n  \
         2.2 minimize          minimise the window (no frames until restore)\n  \
         2.4 restore           map it again\n  \
         2.5 screenshot a.png  the image now (no overlay); prints its `oit render` options\n  \
         3.0 quit",
        keys::BINDINGS
    )
}

/// Everything `oit view` starts from, checked.
pub struct Checked {
    /// The scene.
    pub scene: oit_core::Scene,
    /// The settings other than what the keys change (size, background, max peels).
    pub settings: Settings,
    /// What the window shows first.
    pub state: keys::ViewState,
    /// The scripted events.
    pub script: Vec<script::Event>,
}

/// Every check `oit view` makes before it opens a window: options, script, output path, scene.
pub fn check(args: &ViewArgs) -> Result<Checked, OitError> {
    match args.backend.trim().to_ascii_lowercase().as_str() {
        "wgpu" => {}
        "vulkan" => {
            return Err(OitError::InvalidSettings(
                "--backend vulkan: oit view draws through oit-wgpu's embeddable pass (OitPass) into a \
                 wgpu surface; oit-vulkan has no window path. Use --backend wgpu (its images equal \
                 vulkan's on the reference and the exact techniques), or `oit render --backend vulkan`"
                    .into(),
            ));
        }
        other => {
            return Err(OitError::InvalidSettings(format!(
                "--backend {other}: oit view draws with wgpu only (--backend wgpu)"
            )));
        }
    }
    let technique: Technique = args.technique.parse()?;
    let (width, height) = parse_size(&args.size)?;
    crate::options::check_gltf_scene(&args.scene, args.gltf_scene)?;
    let settings = Settings {
        width,
        height,
        technique,
        background: parse_rgb(&args.background)?,
        alpha: args.alpha,
        max_peels: args.max_peels,
        shading: args.shading.parse()?,
        effect: args.effect.parse()?,
        samples: args.samples,
        ..Settings::default()
    };
    settings.validate()?;
    if matches!(technique, Technique::Mdts { .. }) && args.alpha.is_none() {
        return Err(OitError::Unsupported {
            backend: "oit view".into(),
            what: "mdts: its 32-bit words store no alpha, and the embeddable pass needs one: give --alpha, \
                   or use mdts64"
                .into(),
        });
    }
    if !(1.0..=120.0).contains(&args.fov) {
        return Err(OitError::InvalidSettings(format!(
            "--fov {}: the viewer's field of view is from 1 to 120 degrees",
            args.fov
        )));
    }
    let view =
        View { azimuth: args.azimuth, elevation: args.elevation, fov: args.fov, near: None, far: None };
    let unit = oit_core::Aabb { min: oit_core::glam::Vec3::ZERO, max: oit_core::glam::Vec3::ONE };
    Camera::orbit(&unit, view, width as f32 / height as f32)?;
    if let Some(path) = &args.screenshot {
        check_output(path, "png", "--screenshot")?;
    }
    let script = match &args.script {
        Some(path) => script::load(path)?,
        None => Vec::new(),
    };
    let scene = load_scene_with(&args.scene, args.gltf_scene)?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    scene.validate()?;
    Camera::orbit_scene(&scene, view, width as f32 / height as f32)?;
    let state = keys::ViewState {
        technique,
        view,
        alpha: args.alpha,
        shading: settings.shading,
        effect: settings.effect,
        compare: false,
        overlay: !args.no_overlay,
        p: match technique {
            Technique::Bdp { passes } => passes,
            _ => 1,
        },
        samples: args.samples,
        // until the device says (the window sets it once its device is open)
        max_samples: 8,
    };
    Ok(Checked { scene, settings, state, script })
}

/// Runs `oit view`.
pub fn run(args: &ViewArgs) -> Result<Outcome, OitError> {
    let checked = check(args)?;
    window::run(checked, args)
}
