//! Backends by name: the one place that knows which are compiled in.
//!
//! Adding a backend is one line in [`COMPILED`] (behind its cargo feature); its name is already in
//! [`KNOWN`], so asking for it in a build without it says which feature to turn on.

use oit_core::{Backend, OitError};

/// Options that shape how a backend is built.
#[derive(Clone, Copy, Debug, Default)]
pub struct BackendOptions {
    /// Worker threads of the CPU backend (`None`: one per core).
    #[cfg_attr(not(feature = "cpu"), expect(dead_code, reason = "only the cpu backend has threads"))]
    pub threads: Option<usize>,
}

/// Builds a backend, or says why its device is not there.
type Constructor = fn(&BackendOptions) -> Result<Box<dyn Backend>, OitError>;

/// A backend's name and the backend, or why it is not there.
pub type Probe = (&'static str, Result<Box<dyn Backend>, OitError>);

/// Every backend compiled in, in the order `all` runs them.
const COMPILED: &[(&str, Constructor)] = &[
    #[cfg(feature = "cpu")]
    ("cpu", cpu),
];

/// Every backend oit has, and the cargo feature that compiles it in.
const KNOWN: &[(&str, &str)] = &[("cpu", "cpu"), ("wgpu", "wgpu"), ("vulkan", "vulkan")];

#[cfg(feature = "cpu")]
fn cpu(options: &BackendOptions) -> Result<Box<dyn Backend>, OitError> {
    Ok(Box::new(oit_cpu::CpuBackend { threads: options.threads, ..Default::default() }))
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
