//! Helpers of the conformance suite: the backends compiled in, and one-call renders.
//!
//! Each test body takes a `&dyn Backend` and is run for every backend × raster path [`backends`]
//! returns, so a new backend is tested by adding it there. What a backend or path is expected to
//! do differently lives in one table, [`expectations`], never inside a test.

pub mod checks;
pub mod expectations;

use oit_core::{Backend, Camera, Frame, Scene, Settings, Technique, View, load_scene};

/// Every backend compiled in (cargo features `cpu`, `wgpu`, `vulkan`), once per raster path it has, each
/// pinned to its path ([`oit_core::OnPath`]). A GPU backend without a device is left out with one
/// line on stderr, unless `OIT_REQUIRE_GPU=1` (set by CI), where that is a panic.
pub fn backends() -> Vec<Box<dyn Backend>> {
    backends_labelled("the GPU rows of the conformance suite")
}

/// [`backends`], a missing GPU reported under `label` (the test's name).
fn backends_labelled(label: &str) -> Vec<Box<dyn Backend>> {
    #[cfg_attr(
        not(any(feature = "wgpu", feature = "vulkan")),
        expect(unused_mut, reason = "only GPU backends add paths")
    )]
    let mut out: Vec<Box<dyn Backend>> = Vec::new();
    #[cfg(feature = "cpu")]
    out.push(Box::new(oit_cpu::CpuBackend::default()));
    #[cfg(feature = "wgpu")]
    if oit_wgpu::backend_or_skip(&format!("{label} on wgpu")).is_some() {
        for path in [oit_core::RasterPath::Hardware, oit_core::RasterPath::Compute] {
            out.push(Box::new(oit_core::OnPath {
                backend: Box::new(oit_wgpu::WgpuBackend::default()),
                path,
            }));
        }
    }
    // both paths where the device has a graphics queue and fragment-stage atomics
    #[cfg(feature = "vulkan")]
    if let Some(vk) = oit_vulkan::backend_or_skip(label) {
        for path in oit_core::Backend::capabilities(&vk).raster_paths {
            out.push(Box::new(oit_core::OnPath {
                backend: Box::new(oit_vulkan::VulkanBackend::default()),
                path,
            }));
        }
    }
    out
}

/// [`backends`] less those [`expectations::EXPECTED`] excludes from `test` (each exclusion printed
/// with its reason).
pub fn backends_for(test: &str) -> Vec<Box<dyn Backend>> {
    backends_labelled(test)
        .into_iter()
        .filter(|b| {
            let path = b.raster_path(&Settings::default());
            match expectations::expected(test, b.name(), path) {
                Some(why) => {
                    eprintln!("{test}: not run on {}/{path}: {why}", b.name());
                    false
                }
                None => true,
            }
        })
        .collect()
}

/// [`backends_for`]'s GPU backends (every one but oit-cpu), for tests that hold them to it.
pub fn gpu_backends_for(test: &str) -> Vec<Box<dyn Backend>> {
    backends_for(test).into_iter().filter(|b| b.name() != "cpu").collect()
}

/// `backend`'s name and raster path, as tests print them (`wgpu/hardware`).
pub fn label(backend: &dyn Backend) -> String {
    format!("{}/{}", backend.name(), backend.raster_path(&Settings::default()))
}

/// The CPU backend with a fixed number of threads.
#[cfg(feature = "cpu")]
pub fn cpu_with_threads(threads: usize) -> Box<dyn Backend> {
    Box::new(oit_cpu::CpuBackend::with_threads(Some(threads)))
}

/// A built-in scene (panics on a bad name: tests name only good ones).
pub fn scene(name: &str) -> Scene {
    load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Settings of `size`², the given technique, defaults otherwise.
pub fn settings(size: u32, technique: &str) -> Settings {
    Settings {
        width: size,
        height: size,
        technique: technique.parse().unwrap_or_else(|e| panic!("{e}")),
        ..Settings::default()
    }
}

/// The camera of a view of `scene` for `settings`' aspect ratio.
pub fn camera(scene: &Scene, settings: &Settings, view: View) -> Camera {
    let aspect = settings.width as f32 / settings.height as f32;
    Camera::orbit_scene(scene, view, aspect).expect("camera")
}

/// Renders, panicking with the backend's message on error.
pub fn render(backend: &dyn Backend, scene: &Scene, camera: &Camera, settings: &Settings) -> Frame {
    backend
        .render(scene, camera, settings)
        .unwrap_or_else(|e| panic!("{} {}: {e}", backend.name(), settings.technique))
}

/// Renders `technique` and the reference with the same settings; returns (reference, frame).
pub fn with_reference(
    backend: &dyn Backend,
    scene: &Scene,
    view: View,
    base: &Settings,
    technique: Technique,
) -> (Frame, Frame) {
    let cam = camera(scene, base, view);
    let reference =
        render(backend, scene, &cam, &Settings { technique: Technique::Reference, ..base.clone() });
    let frame = render(backend, scene, &cam, &Settings { technique, ..base.clone() });
    (reference, frame)
}

/// EPR of `technique` against the reference.
pub fn epr(backend: &dyn Backend, scene: &Scene, view: View, base: &Settings, technique: Technique) -> f64 {
    let (r, f) = with_reference(backend, scene, view, base, technique);
    oit_core::metrics::accuracy(&r, &f.image).expect("same size").epr
}

/// Looking straight down −z (planes face the camera).
pub const FRONT: View = View { azimuth: 0.0, elevation: 0.0, fov: 45.0, near: None, far: None };

pub use oit_core::metrics::{differ_off_mask, edge_mask};
