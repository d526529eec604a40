//! The hardware path's graphics-pipeline capture (`hardware_capture: Blend`) against its atomics
//! capture and the reference: dp by depth textures and occlusion queries, ddp by MAX blending
//! (−d, d) into an Rg32Float target, bdp's colour mode by MAX blending into 8 Rgba32Float targets.

use oit_core::{
    Backend, BdpMode, BoundsMode, Camera, Effect, Frame, HardwareCapture, OitError, RasterPath, Settings,
    Technique, View, load_scene,
};

const SCENES: [&str; 3] = ["planes:8", "spheres:4", "knot"];

fn settings(technique: &str, capture: HardwareCapture) -> Settings {
    Settings {
        width: 64,
        height: 64,
        technique: technique.parse::<Technique>().unwrap(),
        raster: Some(RasterPath::Hardware),
        hardware_capture: capture,
        ..Settings::default()
    }
}

fn render(gpu: &oit_wgpu::WgpuBackend, scene_name: &str, s: &Settings) -> Frame {
    let scene = load_scene(scene_name).unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    gpu.render(&scene, &cam, s)
        .unwrap_or_else(|e| panic!("{scene_name} {} {:?}: {e}", s.technique, s.hardware_capture))
}

/// The deepest pixel's fragment count of the reference (N: dp peels N layers in N + 1 passes).
fn depth_complexity(reference: &Frame) -> u32 {
    reference.layers.as_ref().expect("the reference records layers").iter().copied().max().unwrap_or(0)
}

#[test]
fn dp_by_depth_peeling_is_exact() {
    let Some(gpu) = oit_wgpu::backend_or_skip("dp_by_depth_peeling_is_exact") else { return };
    for scene_name in SCENES {
        let reference = render(&gpu, scene_name, &settings("reference", HardwareCapture::Atomics));
        let n = depth_complexity(&reference);
        let blend = render(&gpu, scene_name, &settings("dp", HardwareCapture::Blend));
        let atomics = render(&gpu, scene_name, &settings("dp", HardwareCapture::Atomics));
        let epr = oit_core::metrics::accuracy(&reference, &blend.image).unwrap().epr;
        println!(
            "{scene_name} dp blend: N {n}, passes {} (atomics {}), fragments {} (atomics {}), lost {} (atomics {}), EPR {epr}, storage {} (atomics {}), gpu_ms {:?} (atomics {:?})",
            blend.stats.geometry_passes,
            atomics.stats.geometry_passes,
            blend.stats.fragments,
            atomics.stats.fragments,
            blend.stats.lost,
            atomics.stats.lost,
            blend.stats.storage_bytes,
            atomics.stats.storage_bytes,
            blend.stats.gpu_ms,
            atomics.stats.gpu_ms,
        );
        assert_eq!(epr, 0.0, "{scene_name}: EPR against the reference");
        assert_eq!(blend.stats.geometry_passes, n + 1, "{scene_name}: N + 1 passes");
        assert_eq!(blend.stats.geometry_passes, atomics.stats.geometry_passes, "{scene_name}: passes");
        assert_eq!(blend.stats.fragments, atomics.stats.fragments, "{scene_name}: fragments");
        assert_eq!(blend.stats.lost, atomics.stats.lost, "{scene_name}: lost");
        assert_eq!(blend.stats.lost, 0, "{scene_name}: dp peels everything");
        assert_eq!(blend.image.pixels, atomics.image.pixels, "{scene_name}: image");
    }
}

#[test]
fn dp_by_depth_peeling_stops_at_max_peels() {
    let Some(gpu) = oit_wgpu::backend_or_skip("dp_by_depth_peeling_stops_at_max_peels") else { return };
    for scene_name in SCENES {
        for peels in [1, 2] {
            let s = |c| Settings { max_peels: Some(peels), ..settings("dp", c) };
            let blend = render(&gpu, scene_name, &s(HardwareCapture::Blend));
            let atomics = render(&gpu, scene_name, &s(HardwareCapture::Atomics));
            assert_eq!(blend.stats.geometry_passes, atomics.stats.geometry_passes, "{scene_name} {peels}");
            assert_eq!(blend.stats.lost, atomics.stats.lost, "{scene_name} {peels}: lost");
            assert_eq!(blend.image.pixels, atomics.image.pixels, "{scene_name} {peels}: image");
        }
    }
}

#[test]
fn ddp_by_max_blending_equals_atomics() {
    let Some(gpu) = oit_wgpu::backend_or_skip("ddp_by_max_blending_equals_atomics") else { return };
    for scene_name in SCENES.iter().copied().chain(["coplanar", "cluster:200", "ties:5"]) {
        let reference = render(&gpu, scene_name, &settings("reference", HardwareCapture::Atomics));
        for effect in [Effect::Transparency, Effect::Complexity] {
            let s = |c| Settings { effect, ..settings("ddp", c) };
            let blend = render(&gpu, scene_name, &s(HardwareCapture::Blend));
            let atomics = render(&gpu, scene_name, &s(HardwareCapture::Atomics));
            let what = format!("{scene_name} {effect:?}");
            println!(
                "{what} ddp blend: passes {} (atomics {}), lost {} (atomics {}), storage {} (atomics {})",
                blend.stats.geometry_passes,
                atomics.stats.geometry_passes,
                blend.stats.lost,
                atomics.stats.lost,
                blend.stats.storage_bytes,
                atomics.stats.storage_bytes,
            );
            assert_eq!(blend.image.pixels, atomics.image.pixels, "{what}: image");
            assert_eq!(blend.stats.fragments, atomics.stats.fragments, "{what}: fragments");
            assert_eq!(blend.stats.lost, atomics.stats.lost, "{what}: lost");
            assert_eq!(blend.stats.tied, atomics.stats.tied, "{what}: tied");
            assert_eq!(blend.stats.geometry_passes, atomics.stats.geometry_passes, "{what}: passes");
            assert_eq!(
                blend.stats.storage_bytes,
                atomics.stats.storage_bytes + 16 * 64 * 64,
                "{what}: storage"
            );
            // the tie scenes are ties.rs's: there ddp is right or counts what it may get wrong
            if effect == Effect::Transparency && !["coplanar", "ties:5"].contains(&scene_name) {
                let epr = oit_core::metrics::accuracy(&reference, &blend.image).unwrap().epr;
                assert_eq!(epr, 0.0, "{what}: EPR against the reference");
                let n = depth_complexity(&reference);
                assert_eq!(blend.stats.geometry_passes, n.div_ceil(2) + 1, "{what}: ⌈N/2⌉ + 1 passes");
            }
        }
        // stopped early: the same pairs, one pass more (their payloads arrive a pass later);
        // where peeling ends before the limit, the same passes
        let pairs = depth_complexity(&reference).div_ceil(2);
        for peels in [1, 2] {
            let s = |c| Settings { max_peels: Some(peels), ..settings("ddp", c) };
            let blend = render(&gpu, scene_name, &s(HardwareCapture::Blend));
            let atomics = render(&gpu, scene_name, &s(HardwareCapture::Atomics));
            let what = format!("{scene_name} max_peels {peels}");
            assert_eq!(blend.image.pixels, atomics.image.pixels, "{what}: image");
            assert_eq!(blend.stats.lost, atomics.stats.lost, "{what}: lost");
            assert_eq!(blend.stats.tied, atomics.stats.tied, "{what}: tied");
            let extra = u32::from(pairs + 1 > peels);
            assert_eq!(blend.stats.geometry_passes, atomics.stats.geometry_passes + extra, "{what}: passes");
        }
    }
}

#[test]
fn bdp_by_max_blending_equals_atomics() {
    let Some(gpu) = oit_wgpu::backend_or_skip("bdp_by_max_blending_equals_atomics") else { return };
    for scene_name in SCENES {
        for bounds in [BoundsMode::Boxes, BoundsMode::Exact] {
            let s = |c| Settings { bounds, bdp_mode: BdpMode::Color, ..settings("bdp", c) };
            let blend = render(&gpu, scene_name, &s(HardwareCapture::Blend));
            let atomics = render(&gpu, scene_name, &s(HardwareCapture::Atomics));
            println!(
                "{scene_name} bdp {bounds:?} blend: passes {} (atomics {}), fragments {} (atomics {}), lost {} (atomics {}), storage {} (atomics {}), gpu_ms {:?} (atomics {:?})",
                blend.stats.geometry_passes,
                atomics.stats.geometry_passes,
                blend.stats.fragments,
                atomics.stats.fragments,
                blend.stats.lost,
                atomics.stats.lost,
                blend.stats.storage_bytes,
                atomics.stats.storage_bytes,
                blend.stats.gpu_ms,
                atomics.stats.gpu_ms,
            );
            let what = format!("{scene_name} {bounds:?}");
            assert_eq!(blend.image.pixels, atomics.image.pixels, "{what}: image");
            assert_eq!(blend.stats.fragments, atomics.stats.fragments, "{what}: fragments");
            assert_eq!(blend.stats.lost, atomics.stats.lost, "{what}: lost");
            assert_eq!(blend.stats.geometry_passes, atomics.stats.geometry_passes, "{what}: passes");
            assert_eq!(blend.stats.storage_bytes, atomics.stats.storage_bytes, "{what}: storage");
        }
    }
}

#[test]
fn blend_capture_refuses_what_it_does_not_do() {
    let Some(gpu) = oit_wgpu::backend_or_skip("blend_capture_refuses_what_it_does_not_do") else { return };
    // bdp's depth mode needs (depth, colour) pairs
    let scene = load_scene("planes:8").unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    let s = Settings { bdp_mode: BdpMode::Depth, ..settings("bdp", HardwareCapture::Blend) };
    assert!(matches!(gpu.render(&scene, &cam, &s), Err(OitError::Unsupported { .. })));
    // the compute path ignores the setting
    let s = |c| Settings { raster: Some(RasterPath::Compute), ..settings("dp", c) };
    let a = gpu.render(&scene, &cam, &s(HardwareCapture::Blend)).unwrap();
    let b = gpu.render(&scene, &cam, &s(HardwareCapture::Atomics)).unwrap();
    assert_eq!(a.image.pixels, b.image.pixels);
}

#[test]
fn hardware_capture_parses() {
    assert_eq!("blend".parse::<HardwareCapture>().unwrap(), HardwareCapture::Blend);
    assert_eq!(" Atomics ".parse::<HardwareCapture>().unwrap(), HardwareCapture::Atomics);
    assert!("mrt".parse::<HardwareCapture>().is_err());
    assert_eq!(Settings::default().hardware_capture, HardwareCapture::Atomics);
}
