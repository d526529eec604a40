#![cfg(feature = "wgpu")]
//! dp, ddp, wavg, wsum, mdts, mdts64 and mlp on the compute path against oit-cpu: the same
//! fragments, losses, geometry passes and storage, and the same image (±1 per channel).
//!
//! None of these results depends on the order fragments arrive in: peeling keeps the minimum (and
//! maximum) of (depth, payload) keys, the insertion by atomic min leaves the K smallest words
//! sorted whatever the order, and the weighted sums are integers. So everything is compared, on
//! every scene.

mod common;

use common::{SCENES, compare};
use oit_core::{Backend, Camera, Effect, OitError, RasterPath, Settings, Technique, View, load_scene};

const TECHNIQUES: [&str; 11] =
    ["dp", "ddp", "wavg", "wsum", "mdts", "mdts:4", "mdts64", "mdts64:3", "mlp", "mlp:1", "mlp:3"];

/// On the compute path (the default path of dp, ddp, wavg and wsum is the hardware one).
fn settings(technique: &str) -> Settings {
    Settings {
        width: 64,
        height: 64,
        technique: technique.parse::<Technique>().unwrap(),
        raster: Some(RasterPath::Compute),
        ..Settings::default()
    }
}

#[test]
fn ported_techniques_match_cpu() {
    let Some(gpu) = oit_wgpu::backend_or_skip("ported_techniques_match_cpu") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    for scene_name in SCENES {
        for t in TECHNIQUES {
            compare(&gpu, &cpu, scene_name, &settings(t));
        }
    }
}

#[test]
fn max_peels_and_other_effects_match_cpu() {
    let Some(gpu) = oit_wgpu::backend_or_skip("max_peels_and_other_effects_match_cpu") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    // ties:5: the resolve's tie runs under every effect and peel limit
    for scene_name in ["knot", "cluster:200", "ties:5"] {
        for t in ["dp", "ddp", "mlp:2"] {
            for peels in [1, 2] {
                compare(&gpu, &cpu, scene_name, &Settings { max_peels: Some(peels), ..settings(t) });
            }
        }
        for t in ["dp", "mdts64", "mdts:4", "mlp"] {
            for effect in [Effect::Translucency, Effect::Fresnel, Effect::Complexity] {
                if effect == Effect::Fresnel && t == "mdts:4" {
                    continue;
                }
                compare(&gpu, &cpu, scene_name, &Settings { effect, ..settings(t) });
            }
        }
        for t in ["ddp", "wavg", "wsum"] {
            compare(&gpu, &cpu, scene_name, &Settings { effect: Effect::Complexity, ..settings(t) });
        }
        // a scene-wide alpha override reaches mdts's resolve
        compare(&gpu, &cpu, scene_name, &Settings { alpha: Some(0.3), ..settings("mdts:3") });
    }
}

#[test]
fn unsupported_effects_are_refused() {
    let Some(gpu) = oit_wgpu::backend_or_skip("unsupported_effects_are_refused") else { return };
    let scene = load_scene("planes:4").unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    let cases = [
        ("ddp", Effect::Translucency),
        ("ddp", Effect::Fresnel),
        ("wavg", Effect::Translucency),
        ("wsum", Effect::Fresnel),
        ("mdts", Effect::Fresnel),
    ];
    for (t, effect) in cases {
        let s = Settings { effect, ..settings(t) };
        match gpu.render(&scene, &cam, &s) {
            Err(OitError::Unsupported { what, .. }) => println!("{t} {effect:?}: {what}"),
            other => panic!("{t} {effect:?}: expected Unsupported, got {:?}", other.map(|f| f.stats)),
        }
    }
}
