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
//! A scene (built in, made by hand, or read from an OBJ file), a camera that frames it, and the
//! settings of a frame, each checked before any backend sees them:
//!
//! ```
//! use oit_core::glam::{Mat4, Vec3, Vec4};
//! use oit_core::{
//!     load_scene, parse_obj, Camera, Effect, Instance, Mesh, Object, Scene, Settings, Shading,
//!     Technique, View,
//! };
//!
//! // built in: 4 overlapping quads, 4 layers where they all overlap
//! let planes = load_scene("planes:4")?;
//! assert_eq!(planes.triangle_count(), 8);
//!
//! // by hand: one triangle, a half-transparent red
//! let mesh = Mesh::new("tri", vec![Vec3::new(-1.0, -1.0, 0.0), Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
//! let scene = Scene {
//!     name: "one triangle".into(),
//!     meshes: vec![mesh],
//!     objects: vec![Object::new("red", 0, Vec4::new(1.0, 0.0, 0.0, 0.5))],
//!     instances: vec![Instance { object: 0, transform: Mat4::IDENTITY }],
//!     ..Scene::default()
//! };
//! scene.validate()?;
//!
//! // from OBJ text (a file: `load_obj`, or `load_scene("model.obj")`), vertex colours kept
//! let text = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n";
//! let obj = parse_obj(std::path::Path::new("tri.obj"), text)?;
//! assert!(obj.meshes[0].colors.is_some());
//!
//! // a camera orbiting the scene, fitted to its bounds at a 1:1 aspect
//! let view = View { azimuth: 30.0, elevation: 20.0, ..View::default() };
//! let camera = Camera::orbit_scene(&planes, view, 1.0)?;
//! assert!(camera.near < camera.far);
//!
//! // what one frame is asked for: size, technique (parsed as the command line writes it),
//! // shading and effect
//! let settings = Settings {
//!     width: 64,
//!     height: 64,
//!     technique: "fabs:8".parse::<Technique>()?,
//!     shading: Shading::Headlight,
//!     effect: Effect::Transparency,
//!     ..Settings::default()
//! };
//! settings.validate()?;
//! assert!("fabs:0".parse::<Technique>().is_err()); // a bad parameter is an error, never a panic
//! # Ok::<(), oit_core::OitError>(())
//! ```
//!
//! A [`Backend`] (oit-cpu's `CpuBackend`, oit-wgpu's `WgpuBackend`, oit-vulkan's `VulkanBackend`)
//! turns the three into a [`Frame`]: see those crates' examples.

/// The crate's README (what crates.io shows), whose example runs as a doc test with these.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod assets;
mod backend;
mod camera;
pub mod composite;
mod error;
mod frame;
mod gltf;
mod gltf_write;
pub mod gpu_setup;
pub mod metrics;
pub mod msaa;
pub mod mutation;
mod obj;
pub mod plan;
mod procedural;
pub mod pulled;
mod rng;
pub mod rules;
mod scene;
pub mod scene_set;
mod settings;
pub mod setup;
pub mod technique;
pub mod texture;
pub mod tiling;

pub use backend::{
    AtomicFragmentList, Backend, BucketArray, Capabilities, Compositor, DepthHistogram, LoopEnd, OnPath,
    Prepared, frames_in_flight, frames_one_at_a_time,
};
pub use camera::{Camera, View};
pub use error::OitError;
pub use frame::{Frame, GpuFragments, GpuTotals, Image, Stats};
pub use gltf::{
    GLTF_EXTENSIONS, MAX_VERTICES, is_gltf_path, load_gltf, load_scene_with, parse_gltf, volume_absorption,
};
pub use gltf_write::{pack_glb, write_glb};
pub use obj::{MAX_FACE_CORNERS, load_obj, open_regular, parse_obj};
pub use procedural::{BUILTIN_SCENES, DEFAULT_SCENE, builtin_scene, is_procedural, load_scene};
pub use scene::{Aabb, AlphaMode, Instance, Layers, LayersCache, Mesh, Object, Scene};
pub use settings::{
    AtomicStorage, BdpMode, BlendTarget, HardwareCapture, MAX_SIZE, Overflow, Region, Settings, Shading,
    check_threads, max_threads, parse_memory, parse_rgb, parse_size,
};
pub use technique::{
    BoundsMode, Effect, KNOWN_TECHNIQUES, MAX_PARAMETER, MBOIT_MOMENTS, RasterPath, Sums, Technique,
    TechniqueKind,
};
pub use texture::{Texture, Wrap};

pub use glam;
