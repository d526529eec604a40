//! `oit info`: the backends compiled in, their devices, and what each runs.

use clap::Args;
use oit_bench::backends::{BackendOptions, probe_all};
use oit_core::{BUILTIN_SCENES, KNOWN_TECHNIQUES, OitError, RasterPath, TechniqueKind};
use serde::Serialize;

use crate::Outcome;
use crate::output;

/// Arguments of `oit info`.
#[derive(Args, Debug)]
#[command(
    about = "List the backends compiled in, the device each found, and the techniques each runs",
    long_about = "List the backends compiled in, the device each found, and the techniques each runs.\n\n\
        A backend whose device is missing is listed with the reason and is skipped by \
        --backend all. Also lists the built-in scenes and the technique names. With --json, \
        prints one JSON object {version, backends: [{name, available, device, error, \
        techniques, raster_paths, limits}], scenes, techniques}."
)]
pub struct InfoArgs {
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,

    /// Worker threads the cpu backend would use [default: one per core].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

#[derive(Serialize)]
struct BackendInfo {
    name: &'static str,
    available: bool,
    device: Option<String>,
    error: Option<String>,
    techniques: Vec<TechniqueKind>,
    raster_paths: Vec<RasterPath>,
    limits: serde_json::Map<String, serde_json::Value>,
}

#[derive(Serialize)]
struct Info {
    version: &'static str,
    backends: Vec<BackendInfo>,
    scenes: &'static str,
    techniques: &'static str,
}

/// The lowercase name serde gives a technique kind.
fn kind_name(kind: TechniqueKind) -> String {
    serde_json::to_value(kind)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_else(|| format!("{kind:?}"))
}

/// Every check `oit info` makes: the thread count, bounded by the machine as the other commands
/// bound it.
pub fn check(args: &InfoArgs) -> Result<(), OitError> {
    args.threads.map_or(Ok(()), oit_core::check_threads)
}

/// Runs `oit info`.
pub fn run(args: &InfoArgs) -> Result<Outcome, OitError> {
    check(args)?;
    let backends: Vec<BackendInfo> = probe_all(&BackendOptions { threads: args.threads, adapter: None })
        .into_iter()
        .map(|(name, result)| match result {
            Ok(backend) => {
                let caps = backend.capabilities();
                BackendInfo {
                    name,
                    available: true,
                    device: Some(caps.device),
                    error: None,
                    techniques: caps.techniques,
                    raster_paths: caps.raster_paths,
                    limits: caps.limits.iter().map(|(k, v)| (k.clone(), v.clone().into())).collect(),
                }
            }
            Err(e) => BackendInfo {
                name,
                available: false,
                device: None,
                error: Some(e.to_string()),
                techniques: Vec::new(),
                raster_paths: Vec::new(),
                limits: serde_json::Map::new(),
            },
        })
        .collect();
    let info = Info {
        version: env!("CARGO_PKG_VERSION"),
        backends,
        scenes: BUILTIN_SCENES,
        techniques: KNOWN_TECHNIQUES,
    };
    if args.json {
        return output::print_json(&info).map(|()| Outcome::Success);
    }
    let mut text = format!("oit {}\n\n", info.version);
    if info.backends.is_empty() {
        text.push_str("no backend compiled in: rebuild with --features cpu (or wgpu, vulkan)\n");
    }
    for b in &info.backends {
        text.push_str(&format!("backend {}\n", b.name));
        match (&b.device, &b.error) {
            (Some(device), _) => {
                let list = |v: Vec<String>| {
                    if v.is_empty() { "-".to_string() } else { v.join(", ") }
                };
                text.push_str(&format!("  device      {device}\n"));
                text.push_str(&format!(
                    "  techniques  {}\n",
                    list(b.techniques.iter().map(|&k| kind_name(k)).collect())
                ));
                text.push_str(&format!(
                    "  raster      {}\n",
                    list(b.raster_paths.iter().map(ToString::to_string).collect())
                ));
                for (name, value) in &b.limits {
                    let value = value.as_str().map_or_else(|| value.to_string(), str::to_string);
                    text.push_str(&format!("  limit       {name} = {value}\n"));
                }
            }
            (None, error) => {
                text.push_str(&format!("  unavailable: {}\n", error.as_deref().unwrap_or("no device")));
            }
        }
        text.push('\n');
    }
    text.push_str(&format!("scenes      {}\n", info.scenes));
    text.push_str(&format!("techniques  {}\n", info.techniques));
    output::print(&text)?;
    Ok(Outcome::Success)
}
