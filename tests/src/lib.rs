//! Helpers of the conformance suite: the backends compiled in, and one-call renders.
//!
//! Each test body takes a `&dyn Backend` and is run for every backend [`backends`] returns, so a
//! new backend is tested by adding it there.

use oit_core::{Backend, Camera, Frame, Scene, Settings, Technique, View, load_scene};

/// Every backend compiled in (cargo features `cpu`, later `wgpu`, `vulkan`).
pub fn backends() -> Vec<Box<dyn Backend>> {
    let compiled: [Option<Box<dyn Backend>>; 1] = [
        #[cfg(feature = "cpu")]
        Some(Box::new(oit_cpu::CpuBackend::default())),
        #[cfg(not(feature = "cpu"))]
        None,
    ];
    compiled.into_iter().flatten().collect()
}

/// The CPU backend with a fixed number of threads.
#[cfg(feature = "cpu")]
pub fn cpu_with_threads(threads: usize) -> Box<dyn Backend> {
    Box::new(oit_cpu::CpuBackend { threads: Some(threads), mode: None })
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
pub const FRONT: View = View { azimuth: 0.0, elevation: 0.0, fov: 45.0 };
