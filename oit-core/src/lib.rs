//! oit-core: everything the backends of oit share.
//!
//! - [`Scene`], [`Mesh`], [`Camera`]: what is drawn and from where; OBJ loading ([`load_obj`]) and
//!   built-in procedural scenes ([`builtin_scene`]);
//! - [`Technique`], [`Settings`], [`Frame`]: the catalogue, what a frame is asked for and what comes
//!   back;
//! - [`Backend`] and the capture traits;
//! - [`plan`]: each technique's refusals, sizing and stop rules, executed by every backend;
//! - [`setup`]: triangle setup (clipping, fixed-point snapping, the upload format) every backend
//!   shares;
//! - [`rules`]: the one definition of bucket routing, histogram equalization and packing;
//! - [`composite`]: the compositing equations; [`metrics`]: accuracy against the reference.
//!
//! ```
//! use oit_core::{load_scene, Camera, View};
//! let scene = load_scene("planes:4").unwrap();
//! let camera = Camera::orbit(&scene.bounds(), View::default(), 1.0).unwrap();
//! assert!(camera.near < camera.far);
//! ```

mod backend;
mod camera;
pub mod composite;
mod error;
mod frame;
pub mod metrics;
mod obj;
pub mod plan;
mod procedural;
pub mod rules;
mod scene;
mod settings;
pub mod setup;
mod technique;
pub mod tiling;

pub use backend::{
    AtomicFragmentList, Backend, BucketArray, Capabilities, Compositor, DepthHistogram, OnPath, Prepared,
};
pub use camera::{Camera, View};
pub use error::OitError;
pub use frame::{Frame, Image, Stats};
pub use obj::{load_obj, parse_obj};
pub use procedural::{BUILTIN_SCENES, DEFAULT_SCENE, builtin_scene, load_scene};
pub use scene::{Aabb, Instance, Mesh, Object, Scene};
pub use settings::{
    BdpMode, HardwareCapture, MAX_SIZE, Region, Settings, Shading, check_threads, max_threads, parse_memory,
    parse_rgb, parse_size,
};
pub use technique::{
    BoundsMode, Effect, KNOWN_TECHNIQUES, MAX_PARAMETER, RasterPath, Technique, TechniqueKind,
};

pub use glam;
