//! What one execution runs, per target. Each target takes bytes and either accepts them (and
//! then checks what came out: a scene that validates, a camera that is finite, a frame of the
//! size asked for) or refuses them with oit's own error; a panic, a hang or an allocation past the
//! limit is the failure the harness looks for, and an assertion here is a panic too.
//!
//! - `obj`: the bytes as an OBJ file, parsed in memory (`oit_core::parse_obj`) or, one time in
//!   32, written to a file and loaded (`oit_core::load_obj`, with its size and file-kind checks);
//!   then the scene's bounds and the camera fitted to them.
//! - `scene`: the bytes as a scene expression (`oit_core::load_scene`: built-in names, `grid:`
//!   nesting, file paths), then validation and the camera.
//! - `args`: the bytes as `oit`'s arguments, one a line: clap's parsing, then every check the
//!   command makes before working (`oit_cli::validate`).
//! - `gltf`: the bytes as a glTF file (GLB or `.gltf` JSON) in the worker's scratch folder (its
//!   relative URIs resolve there): `oit_core::parse_gltf` (in memory), or one time in 32 written
//!   and loaded (`oit_core::load_gltf`), one time in four with a scene index of 0 to 3; a scene
//!   that loads must validate and hold triangles, then the camera as for `obj`.
//!
//! A sample of what is accepted (see `--render-every`) is rendered on the CPU backend at 8×8 at
//! most, when the frame's storage is small, to catch what breaks downstream of the checks.

use std::ffi::OsString;
use std::os::unix::ffi::OsStringExt;
use std::path::{Path, PathBuf};

use clap::Parser;
use oit_core::{Backend, Camera, OitError, Scene, Settings, Technique, View};

use crate::Target;

/// The most triangles a sampled render takes (its time grows with them): the default scene's
/// 26,368 and fewer.
const RENDER_MAX_TRIANGLES: u64 = 30_000;

/// The largest technique parameter a sampled render takes: 8×8 pixels of bdp:1024 are 16 MiB;
/// the techniques without one size their storage from the fragments (at most 30,000 a pixel).
const RENDER_MAX_PARAMETER: u32 = 1024;

/// The largest side of a sampled render.
const RENDER_MAX_SIDE: u32 = 8;

/// What one execution came to (a panic aside).
#[derive(Debug)]
pub enum Verdict {
    /// Accepted; `rendered` when a frame was rendered from it too.
    Accepted {
        /// Whether a frame was rendered.
        rendered: bool,
    },
    /// Refused with this error, reduced to a signature (numbers and quoted input left out) so
    /// that refusals of one kind count once.
    Refused(String),
}

/// Per-execution choices the worker makes.
pub struct Ctx {
    /// A folder of the worker's own for files it writes.
    pub scratch: PathBuf,
    /// Whether to render a frame from what is accepted.
    pub render: bool,
    /// Random bits for the other choices (file or memory, view, technique).
    pub bits: u64,
    /// The CPU backend on one thread, for the renders of `obj` and `scene`.
    pub cpu: Box<dyn Backend>,
    /// The worker's folder of FIFOs, which inputs name as `@hostile` ([`crate::hostile`]).
    pub hostile: PathBuf,
}

/// Runs `target` on `input`.
pub fn run(target: Target, input: &[u8], ctx: &Ctx) -> Verdict {
    match target {
        Target::Obj => obj(input, ctx),
        Target::Scene => scene(&crate::hostile::expand(input, &ctx.hostile), ctx),
        Target::Args => args(&crate::hostile::expand(input, &ctx.hostile), ctx),
        Target::Selftest => selftest(input),
        Target::Gltf => gltf(input, ctx),
    }
}

/// The signature of an error: its kind and its message with numbers as `#` and the words that
/// echo the input (quoted, or paths and scene expressions: with `/`, `:` or `.` inside) as `*`.
fn signature(target: Target, e: &OitError) -> String {
    let debug = format!("{e:?}");
    let kind: String = debug.chars().take_while(|c| c.is_alphanumeric()).collect();
    let mut out = format!("{}:{kind}:", target.name());
    let mut quoted = false;
    for word in e.to_string().split_whitespace() {
        let starts = word.starts_with('\'');
        let ends = word.len() > 1 && word.trim_end_matches([',', ';', ')', ':']).ends_with('\'');
        let echo = quoted || starts || word.trim_end_matches([',', ';', ':', ')']).contains(['/', ':', '.']);
        quoted = (quoted || starts) && !ends;
        if echo {
            if !out.ends_with('*') {
                out.push_str(" *");
            }
            continue;
        }
        out.push(' ');
        for c in word.chars() {
            if c.is_ascii_digit() {
                if !out.ends_with('#') {
                    out.push('#');
                }
            } else {
                out.push(c);
            }
        }
        if out.len() > 96 {
            break;
        }
    }
    out
}

fn obj(input: &[u8], ctx: &Ctx) -> Verdict {
    let loaded = if ctx.bits.is_multiple_of(32) {
        let path = ctx.scratch.join("input.obj");
        std::fs::write(&path, input).expect("the worker's scratch folder takes a file");
        oit_core::load_obj(&path)
    } else {
        match std::str::from_utf8(input) {
            Ok(text) => oit_core::parse_obj(Path::new("input.obj"), text),
            Err(_) => return Verdict::Refused("obj:not UTF-8".into()),
        }
    };
    match loaded {
        Ok(scene) => {
            // what loads is what every backend takes: validated, with something to draw
            if let Err(e) = scene.validate() {
                panic!("an OBJ that loaded does not validate: {e}");
            }
            assert!(scene.triangle_count() > 0, "an OBJ that loaded has no triangles");
            // a lone star polygon (huge ones among them) is covered exactly once
            if let Ok(text) = std::str::from_utf8(input) {
                crate::hostile::check_star(text, &scene);
            }
            framed(Target::Obj, &scene, ctx)
        }
        Err(e) => Verdict::Refused(signature(Target::Obj, &e)),
    }
}

fn gltf(input: &[u8], ctx: &Ctx) -> Verdict {
    let path = ctx.scratch.join("input.glb");
    let scene_index = (ctx.bits & 0x30 == 0).then_some(((ctx.bits >> 6) & 3) as usize);
    let loaded = if ctx.bits.is_multiple_of(32) {
        std::fs::write(&path, input).expect("the worker's scratch folder takes a file");
        oit_core::load_gltf(&path, scene_index)
    } else {
        oit_core::parse_gltf(&path, input, scene_index)
    };
    match loaded {
        Ok(scene) => {
            if let Err(e) = scene.validate() {
                panic!("a glTF file that loaded does not validate: {e}");
            }
            assert!(scene.triangle_count() > 0, "a glTF file that loaded has no triangles");
            framed(Target::Gltf, &scene, ctx)
        }
        Err(e) => Verdict::Refused(signature(Target::Gltf, &e)),
    }
}

fn scene(input: &[u8], ctx: &Ctx) -> Verdict {
    let Ok(expr) = std::str::from_utf8(input) else {
        // clap gives the CLI's --scene as a String: non-UTF-8 never reaches load_scene
        return Verdict::Refused("scene:not UTF-8".into());
    };
    match oit_core::load_scene(expr).and_then(|s| s.validate().map(|()| s)) {
        Ok(scene) => framed(Target::Scene, &scene, ctx),
        Err(e) => Verdict::Refused(signature(Target::Scene, &e)),
    }
}

/// Views at the edges of the angles the CLI takes (and past them).
const VIEWS: &[(f32, f32, f32)] = &[
    (30.0, 20.0, 45.0),
    (0.0, 0.0, 0.5),
    (-180.0, 89.0, 179.0),
    (1e30, -89.0, 90.0),
    (359.9, 90.0, 1.0),
    (12.5, -90.0, 178.9),
];

/// The camera fitted to `scene` from a view of [`VIEWS`], checked, and a sampled render.
fn framed(target: Target, scene: &Scene, ctx: &Ctx) -> Verdict {
    let (azimuth, elevation, fov) = VIEWS[(ctx.bits >> 8) as usize % VIEWS.len()];
    let view = View { azimuth, elevation, fov, ..View::default() };
    let camera = match Camera::orbit_scene(scene, view, 1.0) {
        Ok(c) => c,
        Err(e) => return Verdict::Refused(signature(target, &e)),
    };
    check_camera(&camera);
    let settings = Settings { width: RENDER_MAX_SIDE, height: RENDER_MAX_SIDE, ..Settings::default() };
    let rendered = ctx.render && render(ctx.cpu.as_ref(), scene, &camera, &settings);
    Verdict::Accepted { rendered }
}

/// A camera a backend can use: planes in order, matrices finite.
fn check_camera(camera: &Camera) {
    assert!(
        camera.near > 0.0 && camera.near < camera.far && camera.far.is_finite(),
        "camera planes out of order: near {} far {}",
        camera.near,
        camera.far
    );
    assert!(camera.view_proj().is_finite(), "camera matrices not finite: {camera:?}");
    assert!(camera.eye.is_finite() && camera.forward.is_finite(), "camera not finite: {camera:?}");
}

/// Renders one small frame when its triangles and storage are few; true when it rendered.
/// A refusal is fine (a technique may refuse a scene); a frame must have the size asked for and
/// its counters must add up.
fn render(backend: &dyn Backend, scene: &Scene, camera: &Camera, settings: &Settings) -> bool {
    let triangles = scene.triangle_count();
    if triangles > RENDER_MAX_TRIANGLES {
        return false;
    }
    // the storage of a frame grows with the technique's parameter (bdp:P, fabs:K, mdts:K, mlp:M):
    // bdp:65536 at 8×8 is 1 GiB, which oit takes on a host that has it; the harness does not
    let parameter = settings.technique.to_string().split_once(':').and_then(|(_, p)| p.parse::<u32>().ok());
    if parameter.is_some_and(|p| p > RENDER_MAX_PARAMETER) {
        return false;
    }
    match backend.render(scene, camera, settings) {
        Ok(frame) => {
            assert_eq!((frame.image.width, frame.image.height), (settings.width, settings.height));
            let s = &frame.stats;
            assert!(s.captured <= s.fragments, "captured {} of {} fragments", s.captured, s.fragments);
            true
        }
        Err(_) => true,
    }
}

fn args(input: &[u8], ctx: &Ctx) -> Verdict {
    let mut argv = vec![OsString::from("oit")];
    if !input.is_empty() {
        argv.extend(input.split(|&b| b == b'\n').map(|a| OsString::from_vec(a.to_vec())));
    }
    let cli = match oit_cli::Cli::try_parse_from(argv) {
        Ok(cli) => cli,
        Err(e) => {
            // clap's message is what the user sees: build it too
            let _ = e.render().to_string();
            return Verdict::Refused(format!("args:clap:{:?}", e.kind()));
        }
    };
    let validated = match oit_cli::validate(&cli) {
        Ok(v) => v,
        Err(e) => return Verdict::Refused(signature(Target::Args, &e)),
    };
    if let Some(dir) = replot_folder(input) {
        // an accepted report, empty rows and all, is drawn again and read back unchanged
        crate::hostile::round_trip(&dir, &ctx.scratch);
    }
    let Some(prepared) = validated.prepared else { return Verdict::Accepted { rendered: false } };
    let camera = match prepared.camera(prepared.view) {
        Ok(c) => c,
        Err(e) => panic!("validate() passed but the camera fails: {e}"),
    };
    check_camera(&camera);
    let mut rendered = false;
    if ctx.render && !validated.techniques.is_empty() && !prepared.backends.is_empty() {
        let technique: Technique =
            validated.techniques[(ctx.bits >> 16) as usize % validated.techniques.len()];
        let mut settings = prepared.with_technique(technique);
        settings.width = settings.width.min(RENDER_MAX_SIDE);
        settings.height = settings.height.min(RENDER_MAX_SIDE);
        let backend = &prepared.backends[(ctx.bits >> 24) as usize % prepared.backends.len()];
        rendered = render(backend.as_ref(), &prepared.scene, &camera, &settings);
    }
    Verdict::Accepted { rendered }
}

/// The folder of `bench --replot DIR` (or `--replot=DIR`) in a command line that clap and
/// `validate` accepted.
fn replot_folder(input: &[u8]) -> Option<PathBuf> {
    let words: Vec<&[u8]> = input.split(|&b| b == b'\n').collect();
    if words.first() != Some(&&b"bench"[..]) {
        return None;
    }
    let to_path = |w: &[u8]| PathBuf::from(OsString::from_vec(w.to_vec()));
    words.iter().enumerate().rev().find_map(|(i, w)| {
        if let Some(v) = w.strip_prefix(b"--replot=") {
            Some(to_path(v))
        } else if *w == b"--replot" {
            words.get(i + 1).map(|v| to_path(v))
        } else {
            None
        }
    })
}

/// The harness's own check (`--target selftest`): inputs that fail on purpose, one of each kind
/// the harness must catch.
fn selftest(input: &[u8]) -> Verdict {
    match input.trim_ascii() {
        b"panic" => panic!("a planted panic"),
        b"hang" => loop {
            std::thread::sleep(std::time::Duration::from_millis(100));
        },
        b"alloc" => {
            let v = vec![1u8; 1 << 40];
            Verdict::Accepted { rendered: v[v.len() - 1] == 0 }
        }
        b"grow" => {
            // many small allocations, none large on its own (zeroed: calloc touches no page)
            let mut v: Vec<Vec<u8>> = Vec::new();
            loop {
                v.push(vec![0u8; 1 << 20]);
                if v.len() == usize::MAX {
                    return Verdict::Accepted { rendered: false };
                }
            }
        }
        b"deep" => {
            fn deep(n: u64) -> u64 {
                if n == 0 { 0 } else { std::hint::black_box(deep(n - 1)) + 1 }
            }
            Verdict::Accepted { rendered: deep(std::hint::black_box(u64::MAX)) == 0 }
        }
        _ => Verdict::Refused("selftest:fine".into()),
    }
}
