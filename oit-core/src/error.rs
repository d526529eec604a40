//! The one error type of oit: every failure a caller can meet, with a message that says what was
//! wrong and what to do about it.

use std::path::PathBuf;

/// Everything that can go wrong in oit, from a bad scene file to a GPU limit.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OitError {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// An OBJ file could not be parsed.
    #[error("cannot load {path}{}: {message}", line.map(|l| format!(" (line {l})")).unwrap_or_default())]
    Obj {
        /// The file.
        path: PathBuf,
        /// The line, where the parser gives one.
        line: Option<usize>,
        /// What was wrong.
        message: String,
    },
    /// A model file (glTF) that cannot be read as one.
    #[error("cannot load {path}: {message}")]
    Model {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A scene holds data no technique can render (NaN, infinite or out-of-range vertices, bad
    /// indices, nothing, too many triangles).
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// A scene name that is neither built in nor a file.
    #[error(
        "unknown scene '{name}': not a built-in scene, an .obj or glTF (.gltf, .glb) file, or {name}.obj in {searched}; built-in scenes: {known}"
    )]
    UnknownScene {
        /// What was asked for.
        name: String,
        /// The built-in names.
        known: &'static str,
        /// Where else a bare name was looked for.
        searched: &'static str,
    },
    /// A technique name that is not in the catalogue.
    #[error("unknown technique '{name}': {reason}; known techniques: {known}")]
    UnknownTechnique {
        /// What was asked for.
        name: String,
        /// Why it was rejected.
        reason: String,
        /// The catalogue.
        known: &'static str,
    },
    /// A setting out of range (a 0×0 image, a NaN angle, ...).
    #[error("invalid setting: {0}")]
    InvalidSettings(String),
    /// The backend cannot run this technique or path.
    #[error("backend '{backend}' does not support {what}")]
    Unsupported {
        /// The backend.
        backend: String,
        /// What it lacks.
        what: String,
    },
    /// The storage a technique needs exceeds a limit.
    #[error("{what} needs {needed} bytes, over the limit {limit_name} = {limit} bytes; {hint}")]
    TooLarge {
        /// What was to be allocated.
        what: String,
        /// Bytes needed.
        needed: u64,
        /// The limit's name.
        limit_name: String,
        /// The limit.
        limit: u64,
        /// A setting that fits.
        hint: String,
    },
    /// A device was missing or failed.
    #[error("device error: {}", device_message(.0))]
    Device(String),
    /// Writing an image or report failed.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// A [`OitError::Device`] message without the "device error: " its source may already carry (a
/// backend that keeps a failed device's error as text, `e.to_string()`, and wraps it again), so
/// the prefix is printed once.
fn device_message(message: &str) -> &str {
    let mut m = message;
    while let Some(rest) = m.strip_prefix("device error: ") {
        m = rest;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_prefix_is_printed_once() {
        let inner = OitError::Device("no adapter matches 'h100'".into());
        let wrapped = OitError::Device(inner.to_string());
        assert_eq!(wrapped.to_string(), "device error: no adapter matches 'h100'");
        assert_eq!(inner.to_string(), wrapped.to_string());
        // other messages keep their text, even where it mentions a device error later on
        let other = OitError::Device("cannot open: device error: lost".into());
        assert_eq!(other.to_string(), "device error: cannot open: device error: lost");
    }
}
