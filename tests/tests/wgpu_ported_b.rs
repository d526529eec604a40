#![cfg(feature = "wgpu")]
//! bdp (colour and depth modes, bdp:P) and adp on the compute path against oit-cpu: the same
//! fragments, losses, geometry passes and storage, and the same image (±1 per channel).

mod common;

use common::{SCENES, compare};
use oit_core::{
    Backend, BdpMode, BoundsMode, Camera, Effect, OitError, RasterPath, Settings, Technique, View, load_scene,
};

fn settings(technique: &str, bdp_mode: BdpMode, bounds: BoundsMode) -> Settings {
    Settings {
        width: 64,
        height: 64,
        technique: technique.parse::<Technique>().unwrap(),
        bdp_mode,
        bounds,
        raster: Some(RasterPath::Compute),
        ..Settings::default()
    }
}

#[test]
fn bdp_and_adp_match_cpu() {
    let Some(gpu) = oit_wgpu::backend_or_skip("bdp_and_adp_match_cpu") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    let cases = [
        ("bdp", BdpMode::Auto),
        ("bdp", BdpMode::Color),
        ("bdp", BdpMode::Depth),
        ("bdp2", BdpMode::Auto),
        ("bdp:3", BdpMode::Auto),
        ("adp", BdpMode::Auto),
    ];
    for scene_name in SCENES {
        for bounds in [BoundsMode::Boxes, BoundsMode::Exact] {
            for (t, mode) in cases {
                compare(&gpu, &cpu, scene_name, &settings(t, mode, bounds));
            }
        }
    }
}

#[test]
fn max_peels_and_other_effects_match_cpu() {
    let Some(gpu) = oit_wgpu::backend_or_skip("max_peels_and_other_effects_match_cpu") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    for scene_name in ["knot", "cluster:200"] {
        for t in ["bdp:3", "adp"] {
            let s = Settings { max_peels: Some(1), ..settings(t, BdpMode::Auto, BoundsMode::Exact) };
            compare(&gpu, &cpu, scene_name, &s);
        }
        for effect in [Effect::Translucency, Effect::Fresnel, Effect::Complexity] {
            for t in ["bdp", "adp"] {
                let s = Settings { effect, ..settings(t, BdpMode::Auto, BoundsMode::Boxes) };
                compare(&gpu, &cpu, scene_name, &s);
            }
        }
    }
}

/// More than 32 layers: adp runs several batches (and `max_peels` caps them); bdp:P collides.
#[test]
fn deep_scenes_match_cpu() {
    let Some(gpu) = oit_wgpu::backend_or_skip("deep_scenes_match_cpu") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    for scene_name in ["planes:70", "coplanar", "ties:5"] {
        for (t, max_peels) in [("adp", None), ("adp", Some(2)), ("bdp:3", None), ("bdp", None)] {
            for bounds in [BoundsMode::Boxes, BoundsMode::Exact] {
                let s = Settings { max_peels, ..settings(t, BdpMode::Auto, bounds) };
                compare(&gpu, &cpu, scene_name, &s);
            }
        }
    }
}

#[test]
fn colour_mode_rejects_what_cpu_rejects() {
    let Some(gpu) = oit_wgpu::backend_or_skip("colour_mode_rejects_what_cpu_rejects") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    let scene = load_scene("planes:8").unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    let bad = [
        settings("bdp2", BdpMode::Color, BoundsMode::Boxes),
        Settings { effect: Effect::Fresnel, ..settings("bdp", BdpMode::Color, BoundsMode::Boxes) },
    ];
    for s in &bad {
        let g = gpu.render(&scene, &cam, s).unwrap_err();
        let c = cpu.render(&scene, &cam, s).unwrap_err();
        assert!(matches!(g, OitError::InvalidSettings(_)), "{g}");
        assert_eq!(g.to_string(), c.to_string());
    }
}
