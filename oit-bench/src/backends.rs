//! Backends by name: the one registry of oit, shared by the CLI (`render`, `compare`, `sweep`,
//! `bench`, `info`), the bench report and the criterion benches.
//!
//! Contract: [`select`] turns a name (`cpu`, `wgpu`, a comma-separated list, or `all`) into built
//! backends, each compiled in by its cargo feature of this crate (`cpu`, `wgpu`); a backend that
//! is known but not compiled in is an error naming the feature to turn on, and one whose device is
//! missing is an error (or, under `all`, skipped with a note on stderr). [`with_paths`] then pins
//! each backend to the raster paths a [`RasterChoice`] asks for, one [`OnPath`] per path, all
//! paths of one backend sharing one device.
//!
//! Adding a backend is one line in `COMPILED` (behind its cargo feature); its name is already in
//! `KNOWN`, so asking for it in a build without it says which feature to turn on.

use std::sync::Arc;

use oit_core::{
    Backend, Camera, Capabilities, Frame, OitError, OnPath, Prepared, RasterPath, Scene, Settings,
};

/// Options that shape how a backend is built.
#[derive(Clone, Debug, Default)]
pub struct BackendOptions {
    /// Worker threads of the CPU backend (`None`: one per core).
    pub threads: Option<usize>,
    /// GPU adapter name filter.
    pub adapter: Option<String>,
}

/// Which raster paths to run each backend on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RasterChoice {
    /// The backend's own choice per technique.
    Default,
    /// Every path the backend has: one row each.
    All,
    /// This one (backends without it are skipped with a note).
    One(RasterPath),
}

impl RasterChoice {
    /// The choice a `--raster` value makes: a path, `all`, or (left out) the backends' own choice,
    /// except under `--backend all`, which means every backend on every path.
    pub fn parse(raster: Option<&str>, backend: &str) -> Result<RasterChoice, OitError> {
        match raster.map(str::trim) {
            None if backend.split(',').any(|b| b.trim().eq_ignore_ascii_case("all")) => Ok(RasterChoice::All),
            None => Ok(RasterChoice::Default),
            Some(p) if p.eq_ignore_ascii_case("all") => Ok(RasterChoice::All),
            Some(p) => Ok(RasterChoice::One(p.parse::<RasterPath>()?)),
        }
    }
}

/// Pins each backend to the raster paths `choice` asks for.
pub fn with_paths(
    list: Vec<Box<dyn Backend>>,
    choice: RasterChoice,
) -> Result<Vec<Box<dyn Backend>>, OitError> {
    let mut out: Vec<Box<dyn Backend>> = Vec::new();
    for backend in list {
        match choice {
            RasterChoice::Default => out.push(backend),
            RasterChoice::All => {
                let paths = backend.capabilities().raster_paths;
                if paths.len() <= 1 {
                    out.push(backend);
                    continue;
                }
                let shared: Arc<dyn Backend> = Arc::from(backend);
                for path in paths {
                    out.push(Box::new(OnPath { backend: Box::new(Shared(shared.clone())), path }));
                }
            }
            RasterChoice::One(path) => {
                if backend.capabilities().raster_paths.contains(&path) {
                    out.push(Box::new(OnPath { backend, path }));
                } else {
                    eprintln!("note: backend {} has no {path} raster path; skipped", backend.name());
                }
            }
        }
    }
    if out.is_empty() {
        return Err(OitError::InvalidSettings(
            "no selected backend has the raster path asked for (see `oit info`)".into(),
        ));
    }
    Ok(out)
}

/// One backend behind several [`OnPath`]s: one device opened once serves every path.
struct Shared(Arc<dyn Backend>);

impl Backend for Shared {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn capabilities(&self) -> Capabilities {
        self.0.capabilities()
    }
    fn prepare<'s>(&'s self, scene: &'s Scene) -> Result<Box<dyn Prepared + 's>, OitError> {
        self.0.prepare(scene)
    }
    fn render(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        self.0.render(scene, camera, settings)
    }
    fn raster_path(&self, settings: &Settings) -> RasterPath {
        self.0.raster_path(settings)
    }
    fn plain_pass_ms(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<f64, OitError> {
        self.0.plain_pass_ms(scene, camera, settings)
    }
}

/// Builds a backend, or says why its device is not there.
type Constructor = fn(&BackendOptions) -> Result<Box<dyn Backend>, OitError>;

/// A backend's name and the backend, or why it is not there.
pub type Probe = (&'static str, Result<Box<dyn Backend>, OitError>);

/// Every backend compiled in, in the order `all` runs them.
const COMPILED: &[(&str, Constructor)] = &[
    #[cfg(feature = "cpu")]
    ("cpu", cpu),
    #[cfg(feature = "wgpu")]
    ("wgpu", wgpu),
    #[cfg(feature = "vulkan")]
    ("vulkan", vulkan),
];

/// Every backend oit has, and the cargo feature that compiles it in.
const KNOWN: &[(&str, &str)] = &[("cpu", "cpu"), ("wgpu", "wgpu"), ("vulkan", "vulkan")];

#[cfg(feature = "cpu")]
fn cpu(options: &BackendOptions) -> Result<Box<dyn Backend>, OitError> {
    Ok(Box::new(oit_cpu::CpuBackend::with_threads(options.threads)))
}

#[cfg(feature = "wgpu")]
fn wgpu(options: &BackendOptions) -> Result<Box<dyn Backend>, OitError> {
    let backend = oit_wgpu::WgpuBackend::new(options.adapter.clone());
    // open the device now, so a missing one is reported (and skipped by `all`) up front
    backend.gpu()?;
    Ok(Box::new(backend))
}

#[cfg(feature = "vulkan")]
fn vulkan(options: &BackendOptions) -> Result<Box<dyn Backend>, OitError> {
    let backend = oit_vulkan::VulkanBackend::new(options.adapter.clone());
    // open the device now, so a missing one is reported (and skipped by `all`) up front
    backend.gpu()?;
    Ok(Box::new(backend))
}

/// The names of the backends compiled in.
pub fn compiled_names() -> Vec<&'static str> {
    COMPILED.iter().map(|(name, _)| *name).collect()
}

/// Each compiled-in backend by name, built, or the error that says why it could not be (a missing
/// device).
pub fn probe_all(options: &BackendOptions) -> Vec<Probe> {
    COMPILED.iter().map(|(name, make)| (*name, make(options))).collect()
}

/// The backends `name` selects: one name, a comma-separated list, or `all` (every backend compiled
/// in whose device is present; the others are skipped with a note on stderr).
pub fn select(name: &str, options: &BackendOptions) -> Result<Vec<Box<dyn Backend>>, OitError> {
    let compiled = compiled_names().join(", ");
    if COMPILED.is_empty() {
        return Err(OitError::InvalidSettings(
            "no backend is compiled in: rebuild oit with --features cpu (or wgpu, vulkan)".into(),
        ));
    }
    let mut out: Vec<Box<dyn Backend>> = Vec::new();
    for item in name.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let item = item.to_ascii_lowercase();
        if item == "all" {
            for (name, result) in probe_all(options) {
                match result {
                    Ok(b) => out.push(b),
                    Err(e) => eprintln!("note: skipping backend {name}: {e}"),
                }
            }
            if out.is_empty() {
                return Err(OitError::Device(format!(
                    "none of the backends compiled in ({compiled}) found its device; `oit info` says why"
                )));
            }
            continue;
        }
        if let Some((_, make)) = COMPILED.iter().find(|(n, _)| *n == item) {
            out.push(make(options)?);
        } else if let Some((_, feature)) = KNOWN.iter().find(|(n, _)| *n == item) {
            return Err(OitError::InvalidSettings(format!(
                "backend '{item}' is not compiled into this oit: rebuild with `--features {feature}`; \
                 compiled in: {compiled}"
            )));
        } else {
            return Err(OitError::InvalidSettings(format!(
                "unknown backend '{item}': use one of {compiled}, a comma-separated list, or all"
            )));
        }
    }
    if out.is_empty() {
        return Err(OitError::InvalidSettings(format!(
            "--backend '{name}' names no backend: use one of {compiled}, or all"
        )));
    }
    // `all,cpu` and the like: run each backend once.
    let mut seen = Vec::new();
    out.retain(|b| {
        let fresh = !seen.contains(&b.name().to_string());
        seen.push(b.name().to_string());
        fresh
    });
    Ok(out)
}

/// Every backend compiled in whose device is present, on every raster path it has, with a note on
/// stderr for each that is not (`--backend all`; what the benches and tests run).
pub fn available_backends() -> Vec<Box<dyn Backend>> {
    let mut found: Vec<Box<dyn Backend>> = Vec::new();
    for (name, result) in probe_all(&BackendOptions::default()) {
        match result {
            Ok(backend) => found.push(backend),
            Err(e) if name != "cpu" && std::env::var("OIT_REQUIRE_GPU").as_deref() == Ok("1") => {
                panic!("OIT_REQUIRE_GPU=1 but backend {name} is missing: {e}")
            }
            Err(e) => eprintln!("note: backend {name} skipped: {e}"),
        }
    }
    if found.is_empty() {
        return found;
    }
    with_paths(found, RasterChoice::All).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_resolve() {
        let opts = BackendOptions::default();
        if !COMPILED.is_empty() {
            // `all`: every backend compiled in whose device is present (no Vulkan driver: cpu alone)
            let present = probe_all(&opts).iter().filter(|(_, b)| b.is_ok()).count();
            assert_eq!(select("all", &opts).unwrap().len(), present);
            assert_eq!(select(&format!("{},all", COMPILED[0].0), &opts).unwrap().len(), present);
        }
        if !cfg!(feature = "vulkan") {
            let message = select("vulkan", &opts).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(message.contains("--features vulkan"), "{message}");
        }
        assert!(select("nope", &opts).is_err());
        assert!(select("", &opts).is_err());
    }

    #[test]
    fn raster_choices_parse() {
        assert_eq!(RasterChoice::parse(None, "cpu").unwrap(), RasterChoice::Default);
        assert_eq!(RasterChoice::parse(None, "cpu, ALL").unwrap(), RasterChoice::All);
        assert_eq!(RasterChoice::parse(Some("all"), "cpu").unwrap(), RasterChoice::All);
        assert_eq!(
            RasterChoice::parse(Some("compute"), "wgpu").unwrap(),
            RasterChoice::One(RasterPath::Compute)
        );
        assert!(RasterChoice::parse(Some("nope"), "cpu").is_err());
    }

    #[cfg(feature = "cpu")]
    #[test]
    fn one_path_backends_stay_bare() {
        let list = select("cpu", &BackendOptions::default()).unwrap();
        let pinned = with_paths(list, RasterChoice::All).unwrap();
        assert_eq!(pinned.len(), 1);
        assert_eq!(pinned[0].raster_path(&Settings::default()), RasterPath::Cpu);
        let list = select("cpu", &BackendOptions::default()).unwrap();
        assert!(with_paths(list, RasterChoice::One(RasterPath::Compute)).is_err());
    }
}
