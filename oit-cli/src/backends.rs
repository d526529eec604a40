//! Backends by name: the one place that knows which are compiled in.
//!
//! Adding a backend is one line in [`COMPILED`] (behind its cargo feature); its name is already in
//! [`KNOWN`], so asking for it in a build without it says which feature to turn on.

use oit_core::{Backend, OitError, OnPath, RasterPath};

/// Options that shape how a backend is built.
#[derive(Clone, Debug, Default)]
pub struct BackendOptions {
    /// Worker threads of the CPU backend (`None`: one per core).
    #[cfg_attr(not(feature = "cpu"), expect(dead_code, reason = "only the cpu backend has threads"))]
    pub threads: Option<usize>,
    /// GPU adapter name filter.
    #[cfg_attr(not(feature = "wgpu"), expect(dead_code, reason = "only GPU backends have adapters"))]
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
                let name = backend.name().to_string();
                let shared: std::sync::Arc<dyn Backend> = std::sync::Arc::from(backend);
                for path in paths {
                    out.push(Box::new(OnPath { backend: Box::new(Shared(shared.clone())), path }));
                }
                let _ = name;
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

/// One backend behind several [`OnPath`]s (one device opened once).
struct Shared(std::sync::Arc<dyn Backend>);

impl Backend for Shared {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn capabilities(&self) -> oit_core::Capabilities {
        self.0.capabilities()
    }
    fn render(
        &self,
        scene: &oit_core::Scene,
        camera: &oit_core::Camera,
        settings: &oit_core::Settings,
    ) -> Result<oit_core::Frame, OitError> {
        self.0.render(scene, camera, settings)
    }
    fn plain_pass_ms(
        &self,
        scene: &oit_core::Scene,
        camera: &oit_core::Camera,
        settings: &oit_core::Settings,
    ) -> Result<f64, OitError> {
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
];

/// Every backend oit has, and the cargo feature that compiles it in.
const KNOWN: &[(&str, &str)] = &[("cpu", "cpu"), ("wgpu", "wgpu"), ("vulkan", "vulkan")];

#[cfg(feature = "cpu")]
fn cpu(options: &BackendOptions) -> Result<Box<dyn Backend>, OitError> {
    Ok(Box::new(oit_cpu::CpuBackend { threads: options.threads, ..Default::default() }))
}

#[cfg(feature = "wgpu")]
fn wgpu(options: &BackendOptions) -> Result<Box<dyn Backend>, OitError> {
    let backend = oit_wgpu::WgpuBackend::new(options.adapter.clone());
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
pub fn backends(name: &str, options: &BackendOptions) -> Result<Vec<Box<dyn Backend>>, OitError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_resolve() {
        let opts = BackendOptions::default();
        if !COMPILED.is_empty() {
            assert_eq!(backends("all", &opts).unwrap().len(), COMPILED.len());
            assert_eq!(backends(&format!("{},all", COMPILED[0].0), &opts).unwrap().len(), COMPILED.len());
        }
        assert!(backends("wgpu,vulkan,cpu", &opts).is_err() || COMPILED.len() == 3);
        assert!(backends("nope", &opts).is_err());
        assert!(backends("", &opts).is_err());
    }
}
