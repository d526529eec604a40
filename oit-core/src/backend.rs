//! The contract every backend keeps, and the capture abstractions the techniques are built from.
//!
//! A [`Backend`] turns a scene, a camera and settings into a [`Frame`]. Inside, each technique is
//! a *capture* — one or more geometry passes that update per-pixel storage — and a *resolve*
//! that turns each pixel's captured fragments into a colour. The storage comes in four shapes,
//! one trait each, so the CPU's atomics, the GPU's blend units and a GPU's storage buffers can
//! implement the same operation:
//!
//! - [`BucketArray`]: K one-fragment buckets per pixel, updated with MAX;
//! - [`DepthHistogram`]: a 1024-bit per-pixel presence histogram, updated with OR;
//! - [`AtomicFragmentList`]: a per-pixel fixed array, by atomic increment or atomic-min insertion;
//! - [`Compositor`]: sorted fragments to a colour.

use glam::{Vec3, Vec4};
use serde::Serialize;

use crate::rules::HISTOGRAM_WORDS;
use crate::{Camera, Frame, OitError, RasterPath, Scene, Settings, TechniqueKind};

/// What a backend can run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Capabilities {
    /// The device it runs on, in words.
    pub device: String,
    /// Techniques it runs.
    pub techniques: Vec<TechniqueKind>,
    /// Raster paths it has.
    pub raster_paths: Vec<RasterPath>,
    /// Device limits and features that matter to oit, as (name, value).
    pub limits: Vec<(String, String)>,
}

/// A renderer of every technique in its capabilities.
pub trait Backend {
    /// A short name (`cpu`, `wgpu`, `vulkan`).
    fn name(&self) -> &str;
    /// What it can run.
    fn capabilities(&self) -> Capabilities;
    /// Renders one frame. Bad input is an error, never a panic.
    fn render(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Frame, OitError>;
    /// The raster path `render` takes with these settings (the one they name, else the
    /// backend's default for the technique).
    fn raster_path(&self, settings: &Settings) -> RasterPath {
        settings
            .raster
            .or_else(|| self.capabilities().raster_paths.first().copied())
            .unwrap_or(RasterPath::Cpu)
    }
    /// Milliseconds of one plain geometry pass over `scene` (every fragment counted into a
    /// per-pixel atomic counter, nothing else) on the raster path `settings` select: the `Tv` of
    /// DESIGN.md's speedup model `K = N·Tv / (Tv + Tf)`. Device time where the backend measures
    /// it, else wall time; per-frame setup (vertex transform, binning, pipeline creation) is not
    /// counted. The default says the backend cannot.
    fn plain_pass_ms(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<f64, OitError> {
        let _ = (scene, camera, settings);
        Err(OitError::Unsupported {
            backend: self.name().into(),
            what: "timing a plain geometry pass".into(),
        })
    }
}

/// A backend pinned to one raster path: `render` runs with `settings.raster` set to it. This is
/// how a front end lists one row per backend × path.
pub struct OnPath {
    /// The backend.
    pub backend: Box<dyn Backend>,
    /// Its path.
    pub path: RasterPath,
}

impl Backend for OnPath {
    fn name(&self) -> &str {
        self.backend.name()
    }
    fn capabilities(&self) -> Capabilities {
        self.backend.capabilities()
    }
    fn render(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        self.backend.render(scene, camera, &Settings { raster: Some(self.path), ..settings.clone() })
    }
    fn raster_path(&self, _settings: &Settings) -> RasterPath {
        self.path
    }
    fn plain_pass_ms(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<f64, OitError> {
        self.backend.plain_pass_ms(scene, camera, &Settings { raster: Some(self.path), ..settings.clone() })
    }
}

/// K one-fragment buckets per pixel, each updated concurrently with MAX on a 32-bit word (the
/// bits of a non-negative float, or a packed colour).
pub trait BucketArray: Sync {
    /// Buckets per pixel.
    fn buckets(&self) -> usize;
    /// `bucket[pixel][k] = max(bucket[pixel][k], value)`.
    fn update_max(&self, pixel: usize, k: usize, value: u32);
    /// The buckets of one pixel.
    fn read(&self, pixel: usize, out: &mut [u32]);
}

/// A 1024-bit presence histogram per pixel, updated concurrently with OR.
pub trait DepthHistogram: Sync {
    /// Sets bit `bin` of `pixel`'s histogram.
    fn set(&self, pixel: usize, bin: u32);
    /// The histogram of one pixel.
    fn read(&self, pixel: usize) -> [u32; HISTOGRAM_WORDS];
}

/// A fixed array of `capacity` fragment words per pixel, filled concurrently.
pub trait AtomicFragmentList: Sync {
    /// Slots per pixel.
    fn capacity(&self) -> usize;
    /// Offers a fragment key; returns the key that fell off the end, if any (atomic-min insertion
    /// keeps the array sorted and drops the largest; atomic-increment appends and drops overflow).
    fn insert(&self, pixel: usize, key: u64) -> Option<u64>;
    /// The captured keys of one pixel, in depth order.
    fn sorted(&self, pixel: usize, out: &mut Vec<u64>);
}

/// One captured fragment as the resolve sees it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample {
    /// NDC depth.
    pub depth: f32,
    /// Straight-alpha linear colour (transparency) or packed attributes decoded by the effect.
    pub color: Vec4,
    /// The normal, for effects that use it.
    pub normal: Vec3,
}

/// Sorted fragments to a colour.
pub trait Compositor {
    /// The pixel's colour from its fragments, nearest first.
    fn composite(&self, sorted: &[Sample], background: Vec3) -> Vec3;
}
